//! PNG writing of a large picture: the `png` crate on one thread against the banded writer
//! on every core (`render::image::parallel_png`), 8-bit RGB and 16-bit RGBA, 4096 × 4096 of a
//! tone-mapped-looking image (smooth gradients with per-pixel noise, as a path-traced
//! picture has).
//!
//! Run: `cargo bench -p render --bench png`.

use divan::Bencher;
use render::image::parallel_png::{Layout, write, write_serial};

const SIZE: u32 = 4096;

fn picture(layout: Layout) -> Vec<u8> {
    let bpp = layout.channels as usize * if layout.deep { 2 } else { 1 };
    let mut state = 0x2545_f491u32;
    let mut out = Vec::with_capacity(SIZE as usize * SIZE as usize * bpp);
    for y in 0..SIZE {
        for x in 0..SIZE {
            for c in 0..layout.channels as u32 {
                state ^= state << 13;
                state ^= state >> 17;
                state ^= state << 5;
                let smooth = ((x + y * (c + 1)) % 4096) as f32 / 4096.0;
                let v = (smooth * 0.9 + (state % 256) as f32 / 256.0 * 0.1).min(1.0);
                if layout.deep {
                    out.extend(((v * 65535.0) as u16).to_be_bytes());
                } else {
                    out.push((v * 255.0) as u8);
                }
            }
        }
    }
    out
}

const LAYOUTS: [(&str, Layout); 2] = [
    (
        "rgb8",
        Layout {
            channels: 3,
            deep: false,
            srgb: true,
        },
    ),
    (
        "rgba16",
        Layout {
            channels: 4,
            deep: true,
            srgb: true,
        },
    ),
];

#[divan::bench(args = ["rgb8", "rgba16"], sample_count = 5)]
fn png_crate_one_thread(bencher: Bencher, name: &str) {
    let layout = LAYOUTS.iter().find(|l| l.0 == name).unwrap().1;
    let data = picture(layout);
    bencher.bench(|| {
        let mut out = Vec::new();
        write_serial(&mut out, SIZE, SIZE, layout, &data).unwrap();
        out.len()
    });
}

#[divan::bench(args = ["rgb8", "rgba16"], sample_count = 5)]
fn bands_on_every_core(bencher: Bencher, name: &str) {
    let layout = LAYOUTS.iter().find(|l| l.0 == name).unwrap().1;
    let data = picture(layout);
    bencher.bench(|| {
        let mut out = Vec::new();
        write(&mut out, SIZE, SIZE, layout, &data).unwrap();
        out.len()
    });
}

fn main() {
    // What the bands cost in size (each band's deflate starts without the previous window).
    for (name, layout) in LAYOUTS {
        let data = picture(layout);
        let (mut one, mut banded) = (Vec::new(), Vec::new());
        write_serial(&mut one, SIZE, SIZE, layout, &data).unwrap();
        write(&mut banded, SIZE, SIZE, layout, &data).unwrap();
        println!(
            "{name}: {} bytes raw, png crate {} bytes, banded {} bytes",
            data.len(),
            one.len(),
            banded.len()
        );
    }
    divan::main();
}
