//! Text over the image: the HUD, the cheat sheet of keys and load errors,
//! drawn with fontdue from the bundled DejaVu Sans Mono (its licence beside
//! it in `cli/assets`) on a darkened box.

use fontdue::{Font, FontSettings};

/// Pixel height of the text.
pub const TEXT_PX: f32 = 14.0;

/// The bundled monospace font.
static FONT_BYTES: &[u8] = include_bytes!("../../assets/DejaVuSansMono.ttf");

/// Lines of text drawn onto a 0RGB frame buffer.
pub struct Text {
    font: Font,
    advance: usize,
    line: usize,
}

impl Text {
    /// The bundled font at [`TEXT_PX`].
    ///
    /// # Panics
    ///
    /// Never: the font is part of the program (a broken one fails its test).
    #[must_use]
    pub fn new() -> Text {
        let font = Font::from_bytes(FONT_BYTES, FontSettings::default()).expect("the bundled font parses");
        let advance = font.metrics('M', TEXT_PX).advance_width.ceil() as usize;
        Text { font, advance, line: (TEXT_PX * 1.3).ceil() as usize }
    }

    /// The size in pixels of the box [`Text::draw`] fills for `lines`.
    #[must_use]
    pub fn size(&self, lines: &[String]) -> (usize, usize) {
        let cols = lines.iter().map(|l| l.chars().count()).max().unwrap_or(0);
        (cols * self.advance + 8, lines.len() * self.line + 6)
    }

    /// `lines` broken so that their box is at most `width` pixels wide: a
    /// line too long is cut at its last space that fits (mid-word when a
    /// word alone is too long: a file path), the rest indented on the next.
    #[must_use]
    pub fn wrapped(&self, lines: &[String], width: usize) -> Vec<String> {
        let cols = (width.saturating_sub(8) / self.advance).max(8);
        let mut out = Vec::new();
        for line in lines {
            let mut rest: Vec<char> = line.chars().collect();
            let mut indent = 0;
            while indent + rest.len() > cols {
                let room = cols - indent;
                let cut = rest[..=room].iter().rposition(|&c| c == ' ').filter(|&k| k > room / 2).unwrap_or(room);
                let head: String = rest[..cut].iter().collect();
                out.push(format!("{:indent$}{}", "", head.trim_end()));
                rest.drain(..cut);
                while rest.first() == Some(&' ') {
                    rest.remove(0);
                }
                indent = 2;
            }
            out.push(format!("{:indent$}{}", "", rest.iter().collect::<String>()));
        }
        out
    }

    /// Draws `lines` in `colour` (0xRRGGBB) with their top-left corner at
    /// `(x, y)` on a darkened box, into `buffer` (`width` × `height`, 0RGB
    /// row by row); what falls outside is clipped.
    pub fn draw(
        &self,
        buffer: &mut [u32],
        (width, height): (usize, usize),
        (x, y): (usize, usize),
        lines: &[String],
        colour: u32,
    ) {
        let (bw, bh) = self.size(lines);
        for row in y..(y + bh).min(height) {
            for col in x..(x + bw).min(width) {
                let p = &mut buffer[row * width + col];
                *p = (*p >> 2) & 0x003f_3f3f;
            }
        }
        let ascent = self.font.horizontal_line_metrics(TEXT_PX).map_or(TEXT_PX * 0.8, |m| m.ascent);
        for (i, line) in lines.iter().enumerate() {
            let baseline = y as f32 + 3.0 + i as f32 * self.line as f32 + ascent;
            for (k, c) in line.chars().enumerate() {
                let (m, coverage) = self.font.rasterize(c, TEXT_PX);
                let left = (x + 4 + k * self.advance) as i64 + i64::from(m.xmin);
                let top = baseline as i64 - m.height as i64 - i64::from(m.ymin);
                for gy in 0..m.height {
                    for gx in 0..m.width {
                        let (px, py) = (left + gx as i64, top + gy as i64);
                        if px < 0 || py < 0 || px as usize >= width || py as usize >= height {
                            continue;
                        }
                        let a = u32::from(coverage[gy * m.width + gx]);
                        let p = &mut buffer[py as usize * width + px as usize];
                        *p = blend(*p, colour, a);
                    }
                }
            }
        }
    }
}

impl Default for Text {
    fn default() -> Self {
        Text::new()
    }
}

/// `under` moved towards `over` by `a`/255, per 8-bit channel.
fn blend(under: u32, over: u32, a: u32) -> u32 {
    let ch = |s: u32| {
        let (u, o) = ((under >> s) & 0xff, (over >> s) & 0xff);
        ((u * (255 - a) + o * a) / 255) << s
    };
    ch(16) | ch(8) | ch(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Text darkens its box and lights pixels in the colour asked; nothing
    /// is drawn outside the buffer (a box at its corner is clipped).
    #[test]
    fn text_lights_pixels_inside_its_box() {
        let (w, h) = (200, 40);
        let mut buffer = vec![0x0080_8080; w * h];
        let text = Text::new();
        text.draw(&mut buffer, (w, h), (0, 0), &["kage 42 fps".to_string()], 0x00ff_ffff);
        let white = buffer.iter().filter(|&&p| p == 0x00ff_ffff).count();
        assert!(white > 20, "{white} white pixels");
        assert_eq!(buffer[w * h - 1], 0x0080_8080, "outside the box untouched");
        let mut corner = vec![0u32; w * h];
        text.draw(&mut corner, (w, h), (190, 30), &["clipped at the edge".to_string()], 0x00ff_0000);
        assert!(corner.iter().any(|&p| p != 0));
    }

    /// A long error fits the window once wrapped, every word kept, short
    /// lines untouched.
    #[test]
    fn long_lines_wrap_within_the_width() {
        let text = Text::new();
        let long = "error: /home/user/projects/enclosure/parts/lid_with_hinge.scad:117: unknown module \
                    'rounded_cube_with_fillets' (is it in a library not on OPENSCADPATH?)"
            .to_string();
        let lines = vec!["short".to_string(), long.clone()];
        for width in [200, 400, 1280] {
            let wrapped = text.wrapped(&lines, width);
            assert!(text.size(&wrapped).0 <= width, "{width}: {wrapped:?}");
            assert_eq!(wrapped[0], "short");
            let words = |s: &str| s.split_whitespace().collect::<String>();
            assert_eq!(words(&wrapped[1..].concat()), words(&long), "{width}: {wrapped:?}");
        }
        assert_eq!(text.wrapped(&lines, 2000).len(), 2, "a line that fits stays one");
    }
}
