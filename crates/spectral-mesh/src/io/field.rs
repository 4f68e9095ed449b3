//! Per-vertex field files: one number per line, as `numpy.savetxt` writes and
//! `numpy.loadtxt` reads them.
//!
//! # Format read by [`read_field_text`]
//! - one value per line (decimal, with an optional exponent: `1`, `-2.5`, `1e-3`, `.5`);
//! - `#` starts a comment to the end of the line; blank lines and surrounding spaces, tabs
//!   and `\r` are skipped;
//! - NaN and infinities (`nan`, `inf`, `-infinity`, and numbers too large for `f64` such as
//!   `1e400`) are refused: a field must be finite everywhere;
//! - a line with two or more values is refused (this is not a matrix);
//! - when the vertex count `n` is given, the file must hold exactly `n` values.
//!
//! Every error names `origin:line` (1-based) and the problem; a count mismatch names the
//! line of the first value too many, or the file alone when values are missing.
//!
//! # Format written by [`write_field_text`]
//! One value per line in Rust's shortest round-trip notation (`{v:?}`: `0.1`, `1e-7`,
//! `-0.0`, `5e-324`), so both [`read_field_text`] and `numpy.loadtxt` give back the same
//! `f64` bit for bit (negative zero included). Non-finite values are refused before anything
//! is written.

use std::io::Write;
use std::path::Path;

use super::{IoError, atomic_write, read_with};

/// Parses a per-vertex field (format in the module documentation). `origin` labels every
/// error (a file name, `<upload>`, ...); `n`, when given, is the number of values expected
/// (the mesh's vertex count), and reading stops at the first value too many.
pub fn read_field_text(text: &str, origin: &str, n: Option<usize>) -> Result<Vec<f64>, IoError> {
    let err = |line: Option<usize>, message: String| IoError::Invalid {
        path: origin.to_string(),
        line,
        message,
    };
    // A value takes at least two bytes ("0\n") except the last one.
    let cap = text.len() / 2 + 1;
    let mut values = Vec::with_capacity(n.map_or(cap, |n| n.min(cap)));
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let content = raw.split('#').next().unwrap_or("").trim();
        if content.is_empty() {
            continue;
        }
        let mut tokens = content.split_whitespace();
        let (Some(tok), None) = (tokens.next(), tokens.next()) else {
            let count = content.split_whitespace().count();
            return Err(err(
                Some(line),
                format!("{count} values on one line; a field file holds one value per line"),
            ));
        };
        let v: f64 = tok
            .parse()
            .map_err(|_| err(Some(line), format!("'{}' is not a number", shorten(tok))))?;
        if !v.is_finite() {
            return Err(err(
                Some(line),
                format!(
                    "'{}' is not a finite number (NaN, infinite or beyond the range of f64)",
                    shorten(tok)
                ),
            ));
        }
        if let Some(n) = n
            && values.len() == n
        {
            return Err(err(
                Some(line),
                format!("more than {n} values, but the mesh has {n} vertices"),
            ));
        }
        values.push(v);
    }
    if let Some(n) = n
        && values.len() != n
    {
        return Err(err(
            None,
            format!(
                "{} values, but the mesh has {n} vertices (one value per vertex is needed)",
                values.len()
            ),
        ));
    }
    Ok(values)
}

/// Reads a per-vertex field file ([`read_field_text`]); errors name the path.
pub fn read_field(path: &Path, n: Option<usize>) -> Result<Vec<f64>, IoError> {
    read_with(path, |bytes, name| {
        let text = std::str::from_utf8(bytes).map_err(|e| {
            let line = 1 + bytes[..e.valid_up_to()]
                .iter()
                .filter(|&&b| b == b'\n')
                .count();
            IoError::Invalid {
                path: name.to_string(),
                line: Some(line),
                message: "the file is not UTF-8 text".to_string(),
            }
        })?;
        read_field_text(text, name, n)
    })
}

/// The text of a field file: one value per line, shortest round-trip notation. Refuses
/// NaN and infinities (naming the first such index), which [`read_field_text`] would
/// refuse too.
pub fn field_to_text(values: &[f64]) -> Result<String, IoError> {
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(IoError::Invalid {
            path: "<field output>".to_string(),
            line: None,
            message: format!(
                "value {i} is {}; a field file holds finite numbers only",
                values[i]
            ),
        });
    }
    let mut s = String::with_capacity(values.len() * 20);
    for v in values {
        s.push_str(&format!("{v:?}\n"));
    }
    Ok(s)
}

/// Writes a field ([`field_to_text`]) to any writer.
pub fn write_field_text(w: &mut dyn Write, values: &[f64]) -> Result<(), IoError> {
    let s = field_to_text(values)?;
    w.write_all(s.as_bytes()).map_err(|source| IoError::Io {
        path: "<field output>".to_string(),
        action: "write",
        source,
    })
}

/// Writes a field file ([`field_to_text`]) through a temporary file renamed into place,
/// so a failed write leaves any existing file untouched. Nothing is written when a value
/// is not finite.
pub fn write_field(path: &Path, values: &[f64]) -> Result<(), IoError> {
    let name = path.display().to_string();
    let s = field_to_text(values).map_err(|e| match e {
        IoError::Invalid { line, message, .. } => IoError::Invalid {
            path: name.clone(),
            line,
            message,
        },
        other => other,
    })?;
    atomic_write(path, &name, s.as_bytes())
}

fn shorten(tok: &str) -> String {
    if tok.chars().count() > 40 {
        format!("{}...", tok.chars().take(40).collect::<String>())
    } else {
        tok.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn comments_blanks_and_crlf() {
        let v = read_field_text("# header\n1\r\n\n  -2.5e1  # c\n.5\n", "f.txt", Some(3));
        assert_eq!(v.ok(), Some(vec![1.0, -25.0, 0.5]));
    }

    #[test]
    fn errors_name_origin_and_line() {
        let e = read_field_text("1\n2\nx\n", "f.txt", None).unwrap_err();
        assert_eq!(e.to_string(), "f.txt:3: 'x' is not a number");
        let e = read_field_text("1\nnan\n", "f.txt", None).unwrap_err();
        assert!(
            e.to_string().starts_with("f.txt:2: 'nan' is not a finite"),
            "{e}"
        );
        let e = read_field_text("1\n1e400\n", "f.txt", None).unwrap_err();
        assert!(e.to_string().starts_with("f.txt:2: '1e400'"), "{e}");
        let e = read_field_text("1 2\n", "f.txt", None).unwrap_err();
        assert!(
            e.to_string().starts_with("f.txt:1: 2 values on one line"),
            "{e}"
        );
        let e = read_field_text("1\n2\n3\n", "f.txt", Some(2)).unwrap_err();
        assert!(
            e.to_string().starts_with("f.txt:3: more than 2 values"),
            "{e}"
        );
        let e = read_field_text("1\n", "f.txt", Some(2)).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("f.txt: 1 values, but the mesh has 2"),
            "{e}"
        );
    }

    #[test]
    fn written_text_reads_back_bit_for_bit() {
        let v = [
            0.1,
            -0.0,
            5e-324,
            1e300,
            -1.0 / 3.0,
            f64::MAX,
            f64::MIN_POSITIVE,
        ];
        let t = field_to_text(&v).unwrap();
        let back = read_field_text(&t, "rt", Some(v.len())).unwrap();
        assert_eq!(
            v.map(f64::to_bits).to_vec(),
            back.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
        );
        assert!(field_to_text(&[1.0, f64::NAN]).is_err());
    }
}
