//! A small arithmetic expression language for custom spectral filters.
//!
//! Grammar: numbers, the variables `s` (the eigenvalue), `t` and `a` (the page's
//! sliders), the constants `pi` and `e`, the operators `+ - * / ^` (`^` binds tightest,
//! right-associative), parentheses, and the functions `exp log ln sqrt abs sin cos tanh`.

/// A parsed expression.
#[derive(Debug, Clone, PartialEq)]
pub enum Expr {
    /// A constant.
    Num(f64),
    /// A variable: `s`, `t` or `a`.
    Var(char),
    /// `-x`.
    Neg(Box<Expr>),
    /// A binary operation, one of `+ - * / ^`.
    Bin(char, Box<Expr>, Box<Expr>),
    /// A function call.
    Call(String, Box<Expr>),
}

const FUNCTIONS: [&str; 8] = ["exp", "log", "ln", "sqrt", "abs", "sin", "cos", "tanh"];

impl Expr {
    /// Parses `text`; the error names the position and the problem.
    pub fn parse(text: &str) -> Result<Self, String> {
        if text.len() > 500 {
            return Err("the expression is longer than 500 characters".into());
        }
        let mut p = Parser {
            chars: text.chars().collect(),
            pos: 0,
            depth: 0,
        };
        let e = p.sum()?;
        p.skip_ws();
        if p.pos < p.chars.len() {
            return Err(format!(
                "unexpected '{}' at position {}",
                p.chars[p.pos],
                p.pos + 1
            ));
        }
        Ok(e)
    }

    /// Evaluates with `s`, `t`, `a` bound.
    pub fn eval(&self, s: f64, t: f64, a: f64) -> f64 {
        match self {
            Expr::Num(v) => *v,
            Expr::Var('s') => s,
            Expr::Var('t') => t,
            Expr::Var(_) => a,
            Expr::Neg(x) => -x.eval(s, t, a),
            Expr::Bin(op, l, r) => {
                let (l, r) = (l.eval(s, t, a), r.eval(s, t, a));
                match op {
                    '+' => l + r,
                    '-' => l - r,
                    '*' => l * r,
                    '/' => l / r,
                    _ => l.powf(r),
                }
            }
            Expr::Call(f, x) => {
                let x = x.eval(s, t, a);
                match f.as_str() {
                    "exp" => x.exp(),
                    "log" | "ln" => x.ln(),
                    "sqrt" => x.sqrt(),
                    "abs" => x.abs(),
                    "sin" => x.sin(),
                    "cos" => x.cos(),
                    _ => x.tanh(),
                }
            }
        }
    }
}

struct Parser {
    chars: Vec<char>,
    pos: usize,
    depth: usize,
}

impl Parser {
    fn skip_ws(&mut self) {
        while self.pos < self.chars.len() && self.chars[self.pos].is_whitespace() {
            self.pos += 1;
        }
    }
    fn peek(&mut self) -> Option<char> {
        self.skip_ws();
        self.chars.get(self.pos).copied()
    }
    fn sum(&mut self) -> Result<Expr, String> {
        let mut l = self.product()?;
        while let Some(c @ ('+' | '-')) = self.peek() {
            self.pos += 1;
            let r = self.product()?;
            l = Expr::Bin(c, Box::new(l), Box::new(r));
        }
        Ok(l)
    }
    fn product(&mut self) -> Result<Expr, String> {
        let mut l = self.unary()?;
        while let Some(c @ ('*' | '/')) = self.peek() {
            self.pos += 1;
            let r = self.unary()?;
            l = Expr::Bin(c, Box::new(l), Box::new(r));
        }
        Ok(l)
    }
    fn unary(&mut self) -> Result<Expr, String> {
        match self.peek() {
            Some('-') => {
                self.pos += 1;
                Ok(Expr::Neg(Box::new(self.unary()?)))
            }
            Some('+') => {
                self.pos += 1;
                self.unary()
            }
            _ => self.power(),
        }
    }
    fn power(&mut self) -> Result<Expr, String> {
        let base = self.atom()?;
        if self.peek() == Some('^') {
            self.pos += 1;
            let exp = self.unary()?;
            return Ok(Expr::Bin('^', Box::new(base), Box::new(exp)));
        }
        Ok(base)
    }
    fn atom(&mut self) -> Result<Expr, String> {
        self.depth += 1;
        if self.depth > 100 {
            return Err("the expression is nested too deeply".into());
        }
        let r = self.atom_inner();
        self.depth -= 1;
        r
    }
    fn atom_inner(&mut self) -> Result<Expr, String> {
        let start = self.pos;
        match self.peek() {
            None => Err("the expression ends too early".into()),
            Some('(') => {
                self.pos += 1;
                let e = self.sum()?;
                if self.peek() != Some(')') {
                    return Err(format!("missing ')' at position {}", self.pos + 1));
                }
                self.pos += 1;
                Ok(e)
            }
            Some(c) if c.is_ascii_digit() || c == '.' => {
                let s = self.pos;
                while self.pos < self.chars.len()
                    && (self.chars[self.pos].is_ascii_digit()
                        || self.chars[self.pos] == '.'
                        || ((self.chars[self.pos] == 'e' || self.chars[self.pos] == 'E')
                            && self.pos + 1 < self.chars.len()
                            && (self.chars[self.pos + 1].is_ascii_digit()
                                || self.chars[self.pos + 1] == '-'
                                || self.chars[self.pos + 1] == '+'))
                        || ((self.chars[self.pos] == '-' || self.chars[self.pos] == '+')
                            && matches!(self.chars[self.pos - 1], 'e' | 'E')))
                {
                    self.pos += 1;
                }
                let text: String = self.chars[s..self.pos].iter().collect();
                text.parse::<f64>()
                    .map(Expr::Num)
                    .map_err(|_| format!("bad number '{text}' at position {}", s + 1))
            }
            Some(c) if c.is_ascii_alphabetic() => {
                let s = self.pos;
                while self.pos < self.chars.len() && self.chars[self.pos].is_ascii_alphanumeric() {
                    self.pos += 1;
                }
                let name: String = self.chars[s..self.pos].iter().collect();
                match name.as_str() {
                    "s" | "t" | "a" => Ok(Expr::Var(name.chars().next().unwrap_or('s'))),
                    "pi" => Ok(Expr::Num(std::f64::consts::PI)),
                    "e" => Ok(Expr::Num(std::f64::consts::E)),
                    f if FUNCTIONS.contains(&f) => {
                        if self.peek() != Some('(') {
                            return Err(format!("'{f}' must be followed by '('"));
                        }
                        let arg = self.atom()?;
                        Ok(Expr::Call(name, Box::new(arg)))
                    }
                    _ => Err(format!(
                        "unknown name '{name}' at position {}: use s, t, a, pi, e or one of {}",
                        s + 1,
                        FUNCTIONS.join(", ")
                    )),
                }
            }
            Some(c) => Err(format!("unexpected '{c}' at position {}", start + 1)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_evaluates() {
        let e = Expr::parse("(1-a)*exp(-t*s) + a/s^2").unwrap();
        let v = e.eval(2.0, 0.5, 0.25);
        let want = 0.75 * (-1.0f64).exp() + 0.25 / 4.0;
        assert!((v - want).abs() < 1e-14);
        assert_eq!(Expr::parse("-2^2").unwrap().eval(0.0, 0.0, 0.0), -4.0);
        assert_eq!(Expr::parse("2^3^2").unwrap().eval(0.0, 0.0, 0.0), 512.0);
        assert_eq!(Expr::parse("1e-2*s").unwrap().eval(3.0, 0.0, 0.0), 0.03);
    }

    #[test]
    fn rejects_bad_input() {
        for bad in ["", "s +", "foo(s)", "exp s", "(s", "s)", "1..2", "s $ 2"] {
            assert!(Expr::parse(bad).is_err(), "{bad} should not parse");
        }
        let deep = "(".repeat(200) + "s" + &")".repeat(200);
        assert!(Expr::parse(&deep).is_err());
    }
}
