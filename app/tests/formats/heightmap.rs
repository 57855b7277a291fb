//! Heightmap images to terrain: 8- and 16-bit grey and 8-bit colour PNGs, every column's
//! height and its top material against the rule written here; refusals name the file.

use super::*;

/// Writes a PNG of `w` × `h` pixels.
fn png(path: &Path, w: u32, h: u32, colour: png::ColorType, depth: png::BitDepth, data: &[u8]) {
    let file = std::fs::File::create(path).unwrap();
    let mut e = png::Encoder::new(std::io::BufWriter::new(file), w, h);
    e.set_color(colour);
    e.set_depth(depth);
    e.write_header().unwrap().write_image_data(data).unwrap();
}

#[test]
fn heightmaps_become_terrain_column_by_column() {
    let dir = scratch("heightmap");
    let (w, d, height) = (21u32, 13u32, 40u32);
    // A sample per pixel: a ramp along x, a wave along z, some black (no ground).
    let sample = |x: u32, z: u32| -> f64 {
        if x == 3 {
            0.0
        } else {
            (f64::from(x) / f64::from(w - 1)) * 0.8 + (f64::from(z) * 0.7).sin().abs() * 0.2
        }
    };
    let cases = [
        ("grey8.png", png::ColorType::Grayscale, png::BitDepth::Eight),
        (
            "grey16.png",
            png::ColorType::Grayscale,
            png::BitDepth::Sixteen,
        ),
        ("rgb8.png", png::ColorType::Rgb, png::BitDepth::Eight),
    ];
    for (name, colour, depth) in cases {
        let path = dir.join(name);
        let max = if depth == png::BitDepth::Sixteen {
            65535.0
        } else {
            255.0
        };
        let mut data = Vec::new();
        let mut want = Vec::new();
        for z in 0..d {
            for x in 0..w {
                let v = (sample(x, z) * max).round();
                want.push((f64::from(v as u32) / max * f64::from(height)).round() as i32);
                match (colour, depth) {
                    (png::ColorType::Grayscale, png::BitDepth::Sixteen) => {
                        data.extend_from_slice(&(v as u16).to_be_bytes())
                    }
                    (png::ColorType::Grayscale, _) => data.push(v as u8),
                    // Grey in colour: luminance is the same value.
                    _ => data.extend_from_slice(&[v as u8; 3]),
                }
            }
        }
        png(&path, w, d, colour, depth, &data);
        let scene = app::builtin::heightmap_scene(&path, height, 2).unwrap();
        let view = scene.world.read();
        let dims = view.dims().voxels();
        assert_eq!(dims, IVec3::new(24, 40, 16), "{name}: whole bricks");
        let table = view.materials();
        let colour_of = |m: u8| table.colour(table.get(m).unwrap().colour);
        for z in 0..dims.z {
            for x in 0..dims.x {
                let top = (0..dims.y)
                    .rev()
                    .find(|y| view.voxel(IVec3::new(x, *y, z)).unwrap().is_some())
                    .map_or(0, |y| y + 1);
                let expected = if x < w as i32 && z < d as i32 {
                    want[(z * w as i32 + x) as usize]
                } else {
                    0
                };
                assert_eq!(top, expected, "{name}: column ({x}, {z})");
                // Solid all the way down.
                for y in 0..top {
                    assert!(view.voxel(IVec3::new(x, y, z)).unwrap().is_some());
                }
                if top > 0 {
                    let m = view.voxel(IVec3::new(x, top - 1, z)).unwrap().unwrap();
                    let c = colour_of(m);
                    let t = f64::from(top) / f64::from(height);
                    let expected = if t > 0.9 {
                        [240, 244, 250]
                    } else if t > 0.75 {
                        [126, 126, 122]
                    } else {
                        [88, 150, 60]
                    };
                    assert_eq!(c, expected, "{name}: top of ({x}, {z}) at {top}");
                }
            }
        }
    }
    // Refusals name the file: not a PNG, a height past the grid or 0.
    let junk = dir.join("junk.png");
    std::fs::write(&junk, b"not an image").unwrap();
    let e = app::builtin::heightmap_scene(&junk, 40, 1)
        .unwrap_err()
        .to_string();
    assert!(e.contains("junk.png") && e.contains("not a PNG"), "{e}");
    for h in [0, 5000] {
        let e = app::builtin::heightmap_scene(&dir.join("grey8.png"), h, 1)
            .unwrap_err()
            .to_string();
        assert!(e.contains("grey8.png") && e.contains("height"), "{e}");
    }
    let wide = dir.join("wide.png");
    png(
        &wide,
        4097,
        1,
        png::ColorType::Grayscale,
        png::BitDepth::Eight,
        &[7; 4097],
    );
    let e = app::builtin::heightmap_scene(&wide, 40, 1)
        .unwrap_err()
        .to_string();
    assert!(e.contains("at most 4096"), "{e}");
}
