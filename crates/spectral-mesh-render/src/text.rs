//! A tiny built-in 5×7 bitmap font for numeric labels: digits, `.`, `-`, `+`, `e`, `E`
//! and space. Other characters are drawn as blanks.

/// Glyph width in font pixels (without the one-pixel spacing).
pub const GLYPH_W: usize = 5;
/// Glyph height in font pixels.
pub const GLYPH_H: usize = 7;

/// Seven rows, each a 5-character string where `#` is ink.
fn glyph(c: char) -> Option<[&'static str; 7]> {
    Some(match c {
        '0' => [
            ".###.", "#...#", "#..##", "#.#.#", "##..#", "#...#", ".###.",
        ],
        '1' => [
            "..#..", ".##..", "..#..", "..#..", "..#..", "..#..", ".###.",
        ],
        '2' => [
            ".###.", "#...#", "....#", "...#.", "..#..", ".#...", "#####",
        ],
        '3' => [
            "#####", "...#.", "..#..", "...#.", "....#", "#...#", ".###.",
        ],
        '4' => [
            "...#.", "..##.", ".#.#.", "#..#.", "#####", "...#.", "...#.",
        ],
        '5' => [
            "#####", "#....", "####.", "....#", "....#", "#...#", ".###.",
        ],
        '6' => [
            "..##.", ".#...", "#....", "####.", "#...#", "#...#", ".###.",
        ],
        '7' => [
            "#####", "....#", "...#.", "..#..", ".#...", ".#...", ".#...",
        ],
        '8' => [
            ".###.", "#...#", "#...#", ".###.", "#...#", "#...#", ".###.",
        ],
        '9' => [
            ".###.", "#...#", "#...#", ".####", "....#", "...#.", ".##..",
        ],
        '.' => [
            ".....", ".....", ".....", ".....", ".....", ".##..", ".##..",
        ],
        '-' => [
            ".....", ".....", ".....", "#####", ".....", ".....", ".....",
        ],
        '+' => [
            ".....", "..#..", "..#..", "#####", "..#..", "..#..", ".....",
        ],
        'e' | 'E' => [
            ".....", ".....", ".###.", "#...#", "#####", "#....", ".###.",
        ],
        _ => return None,
    })
}

/// Whether font pixel `(x, y)` of `c` is ink.
pub fn ink(c: char, x: usize, y: usize) -> bool {
    match glyph(c) {
        Some(rows) if x < GLYPH_W && y < GLYPH_H => rows[y].as_bytes()[x] == b'#',
        _ => false,
    }
}

/// Width in image pixels of `s` drawn at integer `scale` (one font pixel of spacing
/// between glyphs).
pub fn text_width(s: &str, scale: usize) -> usize {
    let n = s.chars().count();
    if n == 0 {
        0
    } else {
        (n * (GLYPH_W + 1) - 1) * scale
    }
}

/// A short label for a number: up to four significant digits, plain notation for
/// magnitudes in `[1e-3, 1e5)`, scientific (`1.23e-5`) otherwise.
pub fn format_number(x: f64) -> String {
    if !x.is_finite() {
        return "-".to_string();
    }
    if x == 0.0 {
        return "0".to_string();
    }
    let a = x.abs();
    if (1e-3..1e5).contains(&a) {
        let mag = a.log10().floor() as i32;
        let decimals = (3 - mag).max(0) as usize;
        let s = format!("{x:.decimals$}");
        let s = if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        };
        if s == "-0" { "0".to_string() } else { s }
    } else {
        let s = format!("{x:.2e}");
        // Trim zeros of the mantissa: "1.50e-5" -> "1.5e-5".
        match s.split_once('e') {
            Some((m, e)) => {
                let m = if m.contains('.') {
                    m.trim_end_matches('0').trim_end_matches('.')
                } else {
                    m
                };
                format!("{m}e{e}")
            }
            None => s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_label_character_has_a_glyph() {
        for c in "0123456789.-+eE".chars() {
            let g = glyph(c).unwrap();
            assert!(g.iter().all(|r| r.len() == GLYPH_W));
            assert!((0..GLYPH_W).any(|x| (0..GLYPH_H).any(|y| ink(c, x, y))));
        }
        assert!(!ink(' ', 0, 0));
        // Digits are pairwise distinct.
        for a in '0'..='9' {
            for b in '0'..='9' {
                if a != b {
                    assert_ne!(glyph(a), glyph(b));
                }
            }
        }
    }

    #[test]
    fn numbers_format_compactly() {
        assert_eq!(format_number(0.0), "0");
        assert_eq!(format_number(1.0), "1");
        assert_eq!(format_number(-2.5), "-2.5");
        assert_eq!(format_number(0.123456), "0.1235");
        assert_eq!(format_number(1234.6), "1235");
        assert_eq!(format_number(1.5e-5), "1.5e-5");
        assert_eq!(format_number(2.0e7), "2e7");
        assert!(format_number(-3.21e-9).starts_with("-3.21e-9"));
        for x in [1e-7, 0.5, 33.3, -1e9] {
            assert!(format_number(x).chars().all(|c| glyph(c).is_some()));
        }
        assert_eq!(text_width("12", 2), 22);
    }
}
