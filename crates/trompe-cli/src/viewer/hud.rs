//! The viewer's overlay: lines of text drawn with an 8 × 8 bitmap font (the public-domain
//! `font8x8` glyphs) onto a 0RGB frame buffer, white on a darkened band.
//!
//! Invariants: drawing never writes outside the buffer; characters the font lacks draw as `?`.

use font8x8::UnicodeFonts;

/// Pixels a glyph is drawn at (each font pixel a `SCALE × SCALE` block).
pub const SCALE: usize = 2;

/// Draws `lines` at the top left of `buffer` (`width` pixels a row, 0RGB).
pub fn draw(buffer: &mut [u32], width: usize, lines: &[String]) {
    if width == 0 {
        return;
    }
    let height = buffer.len() / width;
    let line_height = 9 * SCALE;
    for (row, line) in lines.iter().enumerate() {
        let y0 = 4 + row * line_height;
        if y0 + line_height > height {
            break;
        }
        let band = (line.chars().count() * 8 * SCALE + 8).min(width);
        for y in y0..y0 + line_height {
            for px in &mut buffer[y * width..y * width + band] {
                // Darken what is behind the text to a quarter.
                *px = (*px >> 2) & 0x3f3f3f;
            }
        }
        for (i, ch) in line.chars().enumerate() {
            let glyph = font8x8::BASIC_FONTS
                .get(ch)
                .or_else(|| font8x8::BASIC_FONTS.get('?'))
                .unwrap_or([0; 8]);
            let x0 = 4 + i * 8 * SCALE;
            for (gy, bits) in glyph.iter().enumerate() {
                for gx in 0..8 {
                    if bits >> gx & 1 == 0 {
                        continue;
                    }
                    for dy in 0..SCALE {
                        for dx in 0..SCALE {
                            let (x, y) = (x0 + gx * SCALE + dx, y0 + gy * SCALE + dy);
                            if x < width && y < height {
                                buffer[y * width + x] = 0xffffff;
                            }
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn text_lands_inside_the_buffer() {
        let mut buffer = vec![0x808080u32; 40 * 30];
        super::draw(
            &mut buffer,
            40,
            &vec!["a long line that overflows".to_string(); 5],
        );
        assert!(buffer.contains(&0xffffff));
        assert!(buffer.contains(&0x202020));
    }
}
