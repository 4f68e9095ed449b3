//! Whitespace-separated tokens with line numbers; `#` starts a comment to the end of line.

/// A token cursor over a byte buffer.
#[derive(Clone)]
pub(crate) struct Lexer<'a> {
    bytes: &'a [u8],
    pos: usize,
    /// 1-based line of `pos`.
    line: usize,
    /// Line of the last token returned.
    last_line: usize,
}

fn is_space(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\r' | b'\x0b' | b'\x0c')
}

impl<'a> Lexer<'a> {
    pub(crate) fn new(bytes: &'a [u8]) -> Self {
        Self {
            bytes,
            pos: 0,
            line: 1,
            last_line: 1,
        }
    }

    /// Line of the last token returned (1 before any).
    pub(crate) fn last_line(&self) -> usize {
        self.last_line
    }

    /// Line the cursor is on (the end of the file once exhausted).
    pub(crate) fn line(&self) -> usize {
        self.line
    }

    fn skip_comment(&mut self) {
        while self.pos < self.bytes.len() && self.bytes[self.pos] != b'\n' {
            self.pos += 1;
        }
    }

    fn take_word(&mut self) -> &'a [u8] {
        let start = self.pos;
        while self.pos < self.bytes.len() {
            let b = self.bytes[self.pos];
            if is_space(b) || b == b'\n' || b == b'#' {
                break;
            }
            self.pos += 1;
        }
        self.last_line = self.line;
        &self.bytes[start..self.pos]
    }

    /// Next token anywhere ahead, skipping blank lines and comments.
    pub(crate) fn next_token(&mut self) -> Option<&'a [u8]> {
        while self.pos < self.bytes.len() {
            let b = self.bytes[self.pos];
            if b == b'\n' {
                self.line += 1;
                self.pos += 1;
            } else if is_space(b) {
                self.pos += 1;
            } else if b == b'#' {
                self.skip_comment();
            } else {
                return Some(self.take_word());
            }
        }
        None
    }

    /// The next token without consuming it.
    pub(crate) fn peek_token(&self) -> Option<&'a [u8]> {
        self.clone().next_token()
    }

    /// Next token on the current line only (`None` at end of line, comment or file).
    pub(crate) fn next_on_line(&mut self) -> Option<&'a [u8]> {
        while self.pos < self.bytes.len() {
            let b = self.bytes[self.pos];
            if b == b'\n' {
                return None;
            } else if is_space(b) {
                self.pos += 1;
            } else if b == b'#' {
                self.skip_comment();
                return None;
            } else {
                return Some(self.take_word());
            }
        }
        None
    }

    /// All remaining tokens on the current line.
    pub(crate) fn rest_of_line(&mut self) -> Vec<&'a [u8]> {
        let mut v = Vec::new();
        while let Some(t) = self.next_on_line() {
            v.push(t);
        }
        v
    }
}

/// Token as text for messages (lossy, shortened).
pub(crate) fn show(tok: &[u8]) -> String {
    let s = String::from_utf8_lossy(tok);
    if s.chars().count() > 40 {
        format!("{}...", s.chars().take(40).collect::<String>())
    } else {
        s.into_owned()
    }
}

/// Parses a decimal float; `None` if not a number (NaN and infinities do parse).
pub(crate) fn parse_f64(tok: &[u8]) -> Option<f64> {
    std::str::from_utf8(tok).ok()?.parse::<f64>().ok()
}

/// Parses a decimal integer.
pub(crate) fn parse_i64(tok: &[u8]) -> Option<i64> {
    std::str::from_utf8(tok).ok()?.parse::<i64>().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_lines_and_comments() {
        let src = b"OFF # header\n\n 3 1 # c\n0 0 0 # x\n1 2#y\n";
        let mut l = Lexer::new(src);
        assert_eq!(l.next_token(), Some(&b"OFF"[..]));
        assert_eq!(l.last_line(), 1);
        assert_eq!(l.next_on_line(), None);
        assert_eq!(l.next_token(), Some(&b"3"[..]));
        assert_eq!(l.last_line(), 3);
        assert_eq!(l.rest_of_line(), vec![&b"1"[..]]);
        assert_eq!(l.next_token(), Some(&b"0"[..]));
        assert_eq!(l.last_line(), 4);
        assert_eq!(l.rest_of_line().len(), 2);
        assert_eq!(l.next_token(), Some(&b"1"[..]));
        assert_eq!(l.rest_of_line(), vec![&b"2"[..]]);
        assert_eq!(l.next_token(), None);
    }
}
