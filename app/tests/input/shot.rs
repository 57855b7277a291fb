//! Screenshots of the Xvfb display read pixel by pixel.

/// An XWD screenshot (Xvfb at depth 24: 32-bit pixels) as a pixel reader.
pub struct Shot {
    bytes: Vec<u8>,
    start: usize,
    line: usize,
    bgr: bool,
}

impl Shot {
    pub fn take(display: &str) -> Self {
        let out = std::process::Command::new("xwd")
            .args(["-root", "-silent", "-display", display])
            .output()
            .expect("xwd runs");
        assert!(out.status.success(), "xwd failed");
        let bytes = out.stdout;
        let word = |i: usize| u32::from_be_bytes(bytes[4 * i..4 * i + 4].try_into().unwrap());
        assert_eq!(word(11), 32, "32-bit pixels");
        let (header, byte_order, line, ncolours) = (
            word(0) as usize,
            word(7),
            word(12) as usize,
            word(19) as usize,
        );
        Self {
            start: header + 12 * ncolours,
            line,
            bgr: byte_order == 0,
            bytes,
        }
    }

    pub fn rgb(&self, x: u32, y: u32) -> [u8; 3] {
        let p = self.start + y as usize * self.line + 4 * x as usize;
        let b = &self.bytes[p..p + 4];
        if self.bgr {
            [b[2], b[1], b[0]]
        } else {
            [b[1], b[2], b[3]]
        }
    }

    /// Whether a pixel is the grass of the terrain (clearly green).
    pub fn grass(&self, x: u32, y: u32) -> bool {
        let [r, g, b] = self.rgb(x, y).map(i32::from);
        g > r + 25 && g > b + 25
    }
}
