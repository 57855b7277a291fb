//! PNG written on every core: the rows are cut into bands, each band filtered (Paeth: it
//! reads the row above, which is the source's, so bands are independent) and deflated on its
//! own thread with a sync flush (a byte-aligned end, no final block), and the pieces written
//! in order as one zlib stream — the header, the bands' deflate data, the last one finishing
//! the stream, and the Adler-32 of the whole filtered data combined from the bands'. Each
//! band's deflate starts without the previous band's window, which costs a little size. One
//! IDAT chunk per band. Small images go through the `png` crate.

use std::io::Write;

/// What a pixel holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// 3 (RGB) or 4 (RGBA).
    pub channels: u8,
    /// 16-bit samples (big-endian, as PNG stores them) instead of 8.
    pub deep: bool,
    /// An sRGB chunk (perceptual intent).
    pub srgb: bool,
}

impl Layout {
    fn bytes_per_pixel(&self) -> usize {
        self.channels as usize * if self.deep { 2 } else { 1 }
    }
}

/// Raw bytes below which the `png` crate writes the image on one thread.
pub const PARALLEL_FROM: usize = 8 << 20;

/// Raw bytes per band (rounded to whole rows).
const BAND_BYTES: usize = 4 << 20;

/// Writes `data` (rows top to bottom, `layout`'s pixels, tightly packed) as a PNG of
/// `width` × `height`.
pub fn write(
    out: &mut dyn Write,
    width: u32,
    height: u32,
    layout: Layout,
    data: &[u8],
) -> std::io::Result<()> {
    let row = width as usize * layout.bytes_per_pixel();
    if data.len() != row * height as usize || !matches!(layout.channels, 3 | 4) {
        return Err(std::io::Error::other(format!(
            "{} bytes are not a {width}x{height} image of {} channels",
            data.len(),
            layout.channels
        )));
    }
    if data.len() < PARALLEL_FROM {
        return write_serial(out, width, height, layout, data);
    }
    write_bands(out, width, height, layout, data, BAND_BYTES)
}

/// [`write`] through the `png` crate on one thread (what small images use; benchmarks).
pub fn write_serial(
    out: &mut dyn Write,
    width: u32,
    height: u32,
    layout: Layout,
    data: &[u8],
) -> std::io::Result<()> {
    let mut encoder = ::png::Encoder::new(out, width, height);
    encoder.set_color(if layout.channels == 4 {
        ::png::ColorType::Rgba
    } else {
        ::png::ColorType::Rgb
    });
    encoder.set_depth(if layout.deep {
        ::png::BitDepth::Sixteen
    } else {
        ::png::BitDepth::Eight
    });
    if layout.srgb {
        encoder.set_source_srgb(::png::SrgbRenderingIntent::Perceptual);
    }
    let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
    writer
        .write_image_data(data)
        .map_err(std::io::Error::other)?;
    writer.finish().map_err(std::io::Error::other)
}

/// The banded writer, bands of about `band_bytes` raw bytes (tests use small ones).
fn write_bands(
    out: &mut dyn Write,
    width: u32,
    height: u32,
    layout: Layout,
    data: &[u8],
    band_bytes: usize,
) -> std::io::Result<()> {
    let bpp = layout.bytes_per_pixel();
    let row = width as usize * bpp;
    let rows_per_band = (band_bytes / row.max(1)).max(1);
    let bands: Vec<(usize, usize)> = (0..height as usize)
        .step_by(rows_per_band)
        .map(|y| (y, (y + rows_per_band).min(height as usize)))
        .collect();
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let next = std::sync::atomic::AtomicUsize::new(0);
    // Each thread takes the next band until none is left; the pieces are then put in order.
    let mut pieces: Vec<(usize, std::io::Result<Piece>)> = std::thread::scope(|s| {
        let workers: Vec<_> = (0..threads.min(bands.len()))
            .map(|_| {
                s.spawn(|| {
                    let mut done = Vec::new();
                    loop {
                        let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some(&rows) = bands.get(k) else { break };
                        done.push((k, band(data, row, bpp, rows, k + 1 == bands.len())));
                    }
                    done
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| w.join().expect("a band's thread does not panic"))
            .collect()
    });
    pieces.sort_by_key(|(k, _)| *k);
    out.write_all(b"\x89PNG\r\n\x1a\n")?;
    let mut ihdr = Vec::with_capacity(13);
    ihdr.extend(width.to_be_bytes());
    ihdr.extend(height.to_be_bytes());
    ihdr.extend([
        if layout.deep { 16 } else { 8 },
        if layout.channels == 4 { 6 } else { 2 },
        0,
        0,
        0,
    ]);
    chunk(out, b"IHDR", &[&ihdr])?;
    if layout.srgb {
        chunk(out, b"sRGB", &[&[0]])?;
    }
    let mut adler = 1u32;
    let count = pieces.len();
    for (k, piece) in pieces {
        let (deflated, band_adler, len) = piece?;
        adler = adler32_combine(adler, band_adler, len as u64);
        // The zlib header (deflate, 32 KiB window, default level) before the first band,
        // the Adler-32 after the last.
        let head: &[u8] = if k == 0 { &[0x78, 0x9c] } else { &[] };
        let tail = if k + 1 == count {
            adler.to_be_bytes().to_vec()
        } else {
            Vec::new()
        };
        chunk(out, b"IDAT", &[head, &deflated, &tail])?;
    }
    chunk(out, b"IEND", &[])
}

/// A band's deflate data, the Adler-32 of its filtered bytes and their length.
type Piece = (Vec<u8>, u32, usize);

/// Rows `y0..y1` filtered with Paeth and deflated: (the deflate data, the filtered bytes'
/// Adler-32, their length). `last` finishes the deflate stream.
fn band(
    data: &[u8],
    row: usize,
    bpp: usize,
    (y0, y1): (usize, usize),
    last: bool,
) -> std::io::Result<Piece> {
    let mut filtered = Vec::with_capacity((y1 - y0) * (row + 1));
    for y in y0..y1 {
        let cur = &data[y * row..(y + 1) * row];
        let up = (y > 0).then(|| &data[(y - 1) * row..y * row]);
        filtered.push(4); // Paeth
        for i in 0..row {
            let a = if i >= bpp { cur[i - bpp] } else { 0 };
            let b = up.map_or(0, |u| u[i]);
            let c = if i >= bpp {
                up.map_or(0, |u| u[i - bpp])
            } else {
                0
            };
            filtered.push(cur[i].wrapping_sub(paeth(a, b, c)));
        }
    }
    let adler = adler32(&filtered);
    let mut deflate = flate2::Compress::new(flate2::Compression::new(4), false);
    let mut out = Vec::with_capacity(filtered.len() / 2 + 64);
    let flush = if last {
        flate2::FlushCompress::Finish
    } else {
        flate2::FlushCompress::Sync
    };
    loop {
        let consumed = deflate.total_in() as usize;
        if out.capacity() - out.len() < 64 {
            out.reserve(out.capacity().max(1 << 16));
        }
        let status = deflate
            .compress_vec(&filtered[consumed..], &mut out, flush)
            .map_err(std::io::Error::other)?;
        let done = deflate.total_in() as usize == filtered.len();
        match status {
            flate2::Status::StreamEnd => break,
            // A sync flush is complete once all input is in and the output had room left.
            _ if !last && done && out.capacity() > out.len() => break,
            _ => {}
        }
    }
    Ok((out, adler, filtered.len()))
}

fn paeth(a: u8, b: u8, c: u8) -> u8 {
    let p = a as i16 + b as i16 - c as i16;
    let (pa, pb, pc) = (
        (p - a as i16).abs(),
        (p - b as i16).abs(),
        (p - c as i16).abs(),
    );
    if pa <= pb && pa <= pc {
        a
    } else if pb <= pc {
        b
    } else {
        c
    }
}

const ADLER_MOD: u32 = 65521;

fn adler32(bytes: &[u8]) -> u32 {
    let (mut a, mut b) = (1u32, 0u32);
    // 5552 bytes is the most that cannot overflow before the modulo.
    for block in bytes.chunks(5552) {
        for &x in block {
            a += x as u32;
            b += a;
        }
        a %= ADLER_MOD;
        b %= ADLER_MOD;
    }
    (b << 16) | a
}

/// The Adler-32 of A followed by B, from each one's and B's length.
fn adler32_combine(a: u32, b: u32, len_b: u64) -> u32 {
    let m = ADLER_MOD as u64;
    let rem = len_b % m;
    let (a1, a2) = ((a & 0xffff) as u64, (a >> 16) as u64);
    let (b1, b2) = ((b & 0xffff) as u64, (b >> 16) as u64);
    let sum1 = (a1 + b1 + m - 1) % m;
    let sum2 = (rem * a1 % m + a2 + b2 + m - rem) % m;
    ((sum2 as u32) << 16) | sum1 as u32
}

fn chunk(out: &mut dyn Write, kind: &[u8; 4], parts: &[&[u8]]) -> std::io::Result<()> {
    let len: usize = parts.iter().map(|p| p.len()).sum();
    out.write_all(&(len as u32).to_be_bytes())?;
    let mut crc = crc32fast::Hasher::new();
    crc.update(kind);
    out.write_all(kind)?;
    for p in parts {
        crc.update(p);
        out.write_all(p)?;
    }
    out.write_all(&crc.finalize().to_be_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decode(png: &[u8]) -> (::png::OutputInfo, Vec<u8>) {
        let mut reader = ::png::Decoder::new(std::io::Cursor::new(png))
            .read_info()
            .unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        buf.truncate(info.buffer_size());
        (info, buf)
    }

    fn pattern(n: usize) -> Vec<u8> {
        (0..n)
            .map(|i| ((i * 7919) ^ (i >> 5)) as u8 / 3 + (i % 97) as u8)
            .collect()
    }

    #[test]
    fn banded_pngs_decode_to_their_pixels_in_every_layout() {
        for (channels, deep) in [(3, false), (4, false), (3, true), (4, true)] {
            let layout = Layout {
                channels,
                deep,
                srgb: true,
            };
            let (w, h) = (37u32, 29u32);
            let data = pattern(w as usize * h as usize * layout.bytes_per_pixel());
            // Bands of a few rows each, the last one shorter.
            let mut out = Vec::new();
            write_bands(&mut out, w, h, layout, &data, 1000).unwrap();
            let (info, pixels) = decode(&out);
            assert_eq!((info.width, info.height), (w, h));
            assert_eq!(info.bit_depth as u8, if deep { 16 } else { 8 });
            assert_eq!(pixels, data, "{channels} channels, deep {deep}");
        }
    }

    #[test]
    fn one_row_bands_and_a_single_band_decode_too() {
        let layout = Layout {
            channels: 3,
            deep: false,
            srgb: false,
        };
        let data = pattern(5 * 4 * 3);
        for band_bytes in [1, 1 << 20] {
            let mut out = Vec::new();
            write_bands(&mut out, 5, 4, layout, &data, band_bytes).unwrap();
            assert_eq!(decode(&out).1, data, "bands of {band_bytes} bytes");
        }
    }

    #[test]
    fn adler_of_parts_combines_to_the_whole() {
        let data = pattern(100_000);
        for cut in [0, 1, 5552, 65521, 70_000, 100_000] {
            let (a, b) = data.split_at(cut);
            assert_eq!(
                adler32_combine(adler32(a), adler32(b), b.len() as u64),
                adler32(&data),
                "cut at {cut}"
            );
        }
    }

    #[test]
    fn a_size_that_does_not_match_is_an_error() {
        let layout = Layout {
            channels: 3,
            deep: false,
            srgb: false,
        };
        assert!(write(&mut Vec::new(), 4, 4, layout, &[0; 47]).is_err());
    }
}
