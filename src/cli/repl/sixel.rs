//! Sixel output for terminals without the kitty or iTerm2 protocols (xterm with sixel, foot,
//! mlterm, …): takes an RGBA image and gives the DEC sixel escape sequence that draws it,
//! downscaled to a preview width, in a fixed 6×6×6 colour cube (deterministic, no
//! quantisation pass).

use std::fmt::Write as _;

/// Widest preview drawn, in pixels (sixel is slow to print for big frames).
pub const MAX_WIDTH: u32 = 480;
const LEVELS: u32 = 6;

/// The sixel sequence for `rgba` (straight alpha; transparent pixels show black).
pub fn encode_sixel(rgba: &[u8], width: u32, height: u32) -> String {
    let scale = (width as f64 / f64::from(MAX_WIDTH)).max(1.0);
    let (w, h) = (
        ((width as f64 / scale).round() as u32).max(1),
        ((height as f64 / scale).round() as u32).max(1),
    );
    let index_at = |x: u32, y: u32| -> usize {
        let sx = ((f64::from(x) + 0.5) * scale) as u32;
        let sy = ((f64::from(y) + 0.5) * scale) as u32;
        let p = ((sy.min(height - 1) * width + sx.min(width - 1)) * 4) as usize;
        let level = |c: u8| (u32::from(c) * (LEVELS - 1) + 127) / 255;
        let a = u32::from(rgba[p + 3]);
        let channel = |c: u8| level(((u32::from(c) * a + 127) / 255) as u8);
        (channel(rgba[p]) * LEVELS * LEVELS + channel(rgba[p + 1]) * LEVELS + channel(rgba[p + 2]))
            as usize
    };
    let mut out = String::new();
    let _ = write!(out, "\x1bP0;1;0q\"1;1;{w};{h}");
    let colours = (LEVELS * LEVELS * LEVELS) as usize;
    for i in 0..colours {
        let percent = |l: usize| l * 100 / (LEVELS as usize - 1);
        let (r, g, b) = (i / 36, (i / 6) % 6, i % 6);
        let _ = write!(out, "#{i};2;{};{};{}", percent(r), percent(g), percent(b));
    }
    let mut bits = vec![0u8; colours * w as usize];
    let mut used = vec![false; colours];
    for band in 0..h.div_ceil(6) {
        bits.fill(0);
        used.fill(false);
        for row in 0..6 {
            let y = band * 6 + row;
            if y >= h {
                break;
            }
            for x in 0..w {
                let c = index_at(x, y);
                bits[c * w as usize + x as usize] |= 1 << row;
                used[c] = true;
            }
        }
        let mut first = true;
        for c in (0..colours).filter(|&c| used[c]) {
            if !first {
                out.push('$');
            }
            first = false;
            let _ = write!(out, "#{c}");
            write_run_length(&mut out, &bits[c * w as usize..(c + 1) * w as usize]);
        }
        out.push('-');
    }
    out.push_str("\x1b\\");
    out
}

/// One colour's row of sixels, with `!n` repeats for runs longer than 3.
fn write_run_length(out: &mut String, sixels: &[u8]) {
    let mut i = 0;
    while i < sixels.len() {
        let value = sixels[i];
        let run = sixels[i..].iter().take_while(|&&s| s == value).count();
        let ch = char::from(63 + value);
        if run > 3 {
            let _ = write!(out, "!{run}{ch}");
        } else {
            (0..run).for_each(|_| out.push(ch));
        }
        i += run;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_uniform_band_is_one_run_of_full_sixels() {
        // 10×6 pure red: one band, colour (5, 0, 0) = index 180, all six bits set ('~').
        let rgba: Vec<u8> = (0..60).flat_map(|_| [255, 0, 0, 255]).collect();
        let s = encode_sixel(&rgba, 10, 6);
        assert!(s.starts_with("\x1bP0;1;0q\"1;1;10;6"));
        assert!(s.ends_with("#180!10~-\x1b\\"), "{s:?}");
    }

    #[test]
    fn rows_map_to_bits_and_bands() {
        // 2×7: row 0 white, rows 1–6 black; second band holds row 6 only.
        let mut rgba = vec![0u8; 2 * 7 * 4];
        for p in rgba.chunks_mut(4) {
            p[3] = 255;
        }
        for p in rgba[..8].chunks_mut(4) {
            p[..3].copy_from_slice(&[255, 255, 255]);
        }
        let s = encode_sixel(&rgba, 2, 7);
        let body = &s[s.rfind("#215;2;100;100;100").unwrap() + "#215;2;100;100;100".len()..];
        // Band 1: black has rows 1–5 (bits 2..=32 → 62 → '}'), white row 0 (bit 1 → '@').
        // Band 2: black row 6 only (bit 1 → '@').
        assert_eq!(body, "#0}}$#215@@-#0@@-\x1b\\");
    }

    #[test]
    fn wide_frames_are_downscaled_to_the_preview_width() {
        let rgba = vec![255u8; 960 * 12 * 4];
        let s = encode_sixel(&rgba, 960, 12);
        assert!(s.starts_with(&format!("\x1bP0;1;0q\"1;1;{MAX_WIDTH};6")));
    }
}
