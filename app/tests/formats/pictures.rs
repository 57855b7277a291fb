//! Finished pictures out (`voxbrick render` to .exr, .pfm and 8 / 16-bit .png), read back by
//! independent readers: the Academy Software Foundation's OpenEXR bindings (PyPI `OpenEXR`,
//! installed with the mesh tools, run by `tests/tools/exr_read.py`) for EXR, the `png` crate
//! for PNG, and a parse written here for PFM. The same picture written as float EXR and PFM
//! holds the same values; half floats round them; with alpha the EXR's colour is
//! premultiplied (0 where alpha is 0) and the 16-bit PNG's alpha is the EXR's quantised.

use super::mesh::{script, tools};
use super::*;
use std::collections::HashMap;
use std::process::Command;

/// Renders the robot at 24 × 18 on the GPU with `extra` options to `out`; None (the test
/// skips, saying so) where there is no Vulkan driver and VOXBRICK_REQUIRE_GPU is not set.
fn render(out: &Path, extra: &[&str]) -> Option<String> {
    let robot = assets().join("mmmm_chr_robot.vox");
    let run = Command::new(env!("CARGO_BIN_EXE_voxbrick"))
        .arg("render")
        .arg(&robot)
        .arg("--out")
        .arg(out)
        .args([
            "--width", "24", "--height", "18", "--spp", "4", "--seed", "3",
        ])
        .args(extra)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr).into_owned();
    if !run.status.success() && stderr.contains("Vulkan") {
        assert!(
            std::env::var("VOXBRICK_REQUIRE_GPU").as_deref() != Ok("1"),
            "no GPU, and VOXBRICK_REQUIRE_GPU=1: {stderr}"
        );
        eprintln!("SKIPPED: no usable Vulkan ({stderr})");
        return None;
    }
    assert!(run.status.success(), "render {extra:?}: {stderr}");
    Some(String::from_utf8_lossy(&run.stdout).into_owned())
}

/// An EXR as the independent reader sees it: width, height, pixel type, channels by name.
fn read_exr(tools: &Path, path: &Path) -> (usize, usize, String, HashMap<String, Vec<f64>>) {
    let out = Command::new(tools.join("venv/bin/python"))
        .arg(script("exr_read.py"))
        .arg(path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "exr_read.py: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let channels = v["channels"]
        .as_object()
        .unwrap()
        .iter()
        .map(|(k, c)| {
            let values = c.as_array().unwrap().iter().map(|x| x.as_f64().unwrap());
            (k.clone(), values.collect())
        })
        .collect();
    (
        v["width"].as_u64().unwrap() as usize,
        v["height"].as_u64().unwrap() as usize,
        v["type"].as_str().unwrap().to_string(),
        channels,
    )
}

/// A colour PFM's pixels, rows top to bottom.
fn read_pfm(path: &Path) -> (usize, usize, Vec<[f32; 3]>) {
    let bytes = std::fs::read(path).unwrap();
    let text = String::from_utf8_lossy(&bytes[..bytes.len().min(64)]).into_owned();
    let mut lines = text.splitn(4, '\n');
    assert_eq!(lines.next(), Some("PF"));
    let dims: Vec<usize> = lines
        .next()
        .unwrap()
        .split(' ')
        .map(|d| d.parse().unwrap())
        .collect();
    assert_eq!(lines.next(), Some("-1.0"), "little-endian");
    let header = text
        .splitn(4, '\n')
        .take(3)
        .map(|l| l.len() + 1)
        .sum::<usize>();
    let (w, h) = (dims[0], dims[1]);
    let floats: Vec<f32> = bytes[header..]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(floats.len(), w * h * 3);
    let mut pixels = vec![[0.0; 3]; w * h];
    for y in 0..h {
        for x in 0..w {
            let k = ((h - 1 - y) * w + x) * 3;
            pixels[y * w + x] = [floats[k], floats[k + 1], floats[k + 2]];
        }
    }
    (w, h, pixels)
}

#[test]
fn pictures_are_read_back_by_independent_readers() {
    let Some(tools) = tools() else { return };
    let d = scratch("pictures");
    // One invocation per pixel: the same picture twice holds the same values.
    let same = ["--slices", "1"];
    let pfm = d.join("robot.pfm");
    let Some(text) = render(&pfm, &same) else {
        return;
    };
    assert!(text.contains("PFM"), "{text}");
    let (w, h, linear) = read_pfm(&pfm);
    assert_eq!((w, h), (24, 18));
    let lum: f32 = linear.iter().map(|p| p[0] + p[1] + p[2]).sum();
    assert!(lum > 0.0, "a black picture");
    let close = |a: f64, b: f32, tol: f64| (a - b as f64).abs() <= tol * (1.0 + b.abs() as f64);
    // Float EXR: the PFM's values (atomic sums of the shadow queue may differ in the last bit).
    let exr = d.join("robot.exr");
    render(&exr, &same).unwrap();
    let (ew, eh, ty, ch) = read_exr(&tools, &exr);
    assert_eq!((ew, eh, ty.as_str()), (24, 18, "float32"));
    assert_eq!(ch.len(), 3, "{:?}", ch.keys());
    for (i, p) in linear.iter().enumerate() {
        for (c, name) in ["R", "G", "B"].iter().enumerate() {
            assert!(
                close(ch[*name][i], p[c], 1e-5),
                "{name} {i}: {} vs {}",
                ch[*name][i],
                p[c]
            );
        }
    }
    // Half floats: rounded to 11 significant bits.
    let half = d.join("robot_half.exr");
    render(&half, &[&same[..], &["--half"]].concat()).unwrap();
    let (_, _, ty, ch) = read_exr(&tools, &half);
    assert_eq!(ty, "float16");
    for (i, p) in linear.iter().enumerate() {
        assert!(
            close(ch["R"][i], p[0], 1e-3),
            "R {i}: {} vs {}",
            ch["R"][i],
            p[0]
        );
    }
    // Alpha: premultiplied colour in the EXR; the 16-bit PNG's alpha is the EXR's.
    let (ea, pa) = (d.join("robot_alpha.exr"), d.join("robot_alpha.png"));
    render(&ea, &[&same[..], &["--alpha", "--view", "iso"]].concat()).unwrap();
    render(
        &pa,
        &[&same[..], &["--alpha", "--view", "iso", "--png16"]].concat(),
    )
    .unwrap();
    let (_, _, _, ch) = read_exr(&tools, &ea);
    let alpha = &ch["A"];
    assert!(alpha.contains(&0.0) && alpha.contains(&1.0));
    for (i, &a) in alpha.iter().enumerate() {
        assert!((0.0..=1.0).contains(&a));
        if a == 0.0 {
            assert_eq!([ch["R"][i], ch["G"][i], ch["B"][i]], [0.0; 3], "pixel {i}");
        }
    }
    let mut decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&pa).unwrap()));
    decoder.set_transformations(png::Transformations::IDENTITY);
    let mut reader = decoder.read_info().unwrap();
    let info = reader.info().clone();
    assert_eq!(
        (info.width, info.height, info.color_type, info.bit_depth),
        (24, 18, png::ColorType::Rgba, png::BitDepth::Sixteen)
    );
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    reader.next_frame(&mut buf).unwrap();
    for (i, &a) in alpha.iter().enumerate() {
        let k = i * 8 + 6;
        let png_alpha = u16::from_be_bytes([buf[k], buf[k + 1]]);
        assert_eq!(png_alpha, (a * 65535.0 + 0.5) as u16, "pixel {i}");
    }
    // Sequences: a turntable's frames and a camera path's, numbered, each its own view.
    let turn = d.join("turn.png");
    let text = render(&turn, &["--turntable", "3"]).unwrap();
    let frames: Vec<Vec<u8>> = (0..3)
        .map(|k| std::fs::read(d.join(format!("turn_{k:04}.png"))).unwrap())
        .collect();
    assert!(frames[0] != frames[1] && frames[1] != frames[2], "{text}");
    assert!(!d.join("turn_0003.png").exists());
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/bench/thesis_path.ron");
    let walk = d.join("walk.png");
    // 20 s at 0.1 frames per second: t = 0, 10 and 20 s.
    render(&walk, &["--path", path.to_str().unwrap(), "--fps", "0.1"]).unwrap();
    assert!(d.join("walk_0002.png").exists() && !d.join("walk_0003.png").exists());
    // A PFM has no alpha: refused before anything is written.
    let no = d.join("no.pfm");
    let run = Command::new(env!("CARGO_BIN_EXE_voxbrick"))
        .args([
            "render",
            assets().join("mmmm_chr_robot.vox").to_str().unwrap(),
        ])
        .arg("--out")
        .arg(&no)
        .arg("--alpha")
        .output()
        .unwrap();
    assert!(!run.status.success());
    assert!(String::from_utf8_lossy(&run.stderr).contains("PFM has no alpha"));
    assert!(!no.exists());
}
