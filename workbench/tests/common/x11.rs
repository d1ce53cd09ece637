//! A virtual X display for the window tests: Xvfb, synthetic input with xdotool, screenshots
//! with xwd.

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};

pub fn have(tool: &str) -> bool {
    Command::new("sh")
        .args(["-c", &format!("command -v {tool}")])
        .output()
        .is_ok_and(|o| o.status.success())
}

/// True when the X tools are here; under CI their absence fails the test.
pub fn x_tools() -> bool {
    let missing: Vec<&str> = ["Xvfb", "xdotool", "xwd"]
        .into_iter()
        .filter(|t| !have(t))
        .collect();
    if missing.is_empty() {
        return true;
    }
    assert!(
        std::env::var_os("CI").is_none(),
        "{missing:?} missing under CI (.ci/run installs xvfb xdotool x11-apps)"
    );
    eprintln!("skipped: {missing:?} not installed");
    false
}

/// A virtual X display of this test alone, killed when dropped.
pub struct Xvfb {
    child: Child,
    pub display: String,
}

impl Xvfb {
    pub fn start() -> Xvfb {
        let mut child = Command::new("Xvfb")
            .args([
                "-displayfd",
                "1",
                "-screen",
                "0",
                "1280x720x24",
                "-nolisten",
                "tcp",
            ])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("Xvfb starts");
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap())
            .read_line(&mut line)
            .unwrap();
        let n: u32 = line.trim().parse().expect("Xvfb prints its display number");
        Xvfb {
            child,
            display: format!(":{n}"),
        }
    }

    pub fn xdotool(&self, args: &[&str]) {
        let out = Command::new("xdotool")
            .args(args)
            .env("DISPLAY", &self.display)
            .output()
            .unwrap();
        assert!(out.status.success(), "xdotool {args:?}: {out:?}");
    }

    /// The screen, RGB8.
    pub fn screenshot(&self) -> image::RgbImage {
        let out = Command::new("xwd")
            .args(["-root", "-silent", "-display", &self.display])
            .output()
            .unwrap();
        assert!(out.status.success(), "xwd: {out:?}");
        read_xwd(&out.stdout)
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Decodes an XWD image (ZPixmap, 24 or 32 bits per pixel, as Xvfb's root window is).
pub fn read_xwd(b: &[u8]) -> image::RgbImage {
    let be = |i: usize| u32::from_be_bytes(b[4 * i..4 * i + 4].try_into().unwrap());
    let (header, width, height) = (be(0) as usize, be(4), be(5));
    let (byte_order, bpp, stride) = (be(7), be(11) as usize, be(12) as usize);
    let masks = [be(14), be(15), be(16)];
    let ncolors = be(19) as usize;
    assert!(bpp == 32 || bpp == 24, "xwd: {bpp} bits per pixel");
    let data = &b[header + 12 * ncolors..];
    let mut img = image::RgbImage::new(width, height);
    for y in 0..height as usize {
        for x in 0..width as usize {
            let o = y * stride + x * bpp / 8;
            let mut px = [0u8; 4];
            px[..bpp / 8].copy_from_slice(&data[o..o + bpp / 8]);
            let v = if byte_order == 0 {
                u32::from_le_bytes(px)
            } else {
                u32::from_be_bytes(px) >> (32 - bpp)
            };
            let ch = |m: u32| ((v & m) >> m.trailing_zeros()) as u8;
            img.put_pixel(
                x as u32,
                y as u32,
                image::Rgb([ch(masks[0]), ch(masks[1]), ch(masks[2])]),
            );
        }
    }
    img
}
