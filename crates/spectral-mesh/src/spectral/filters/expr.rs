//! A small safe expression language for custom filters.

use super::FilterError;

/// Deepest nesting of parentheses, function calls, unary signs and powers in a custom
/// expression.
pub const MAX_EXPR_NESTING: usize = 64;

/// Most numbers, names and operations in a custom expression.
pub const MAX_EXPR_NODES: usize = 1000;

/// A parsed expression in `s` and named parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct Expr {
    node: Node,
}

#[derive(Debug, Clone, PartialEq)]
enum Node {
    Num(f64),
    S,
    Param(usize),
    Neg(Box<Node>),
    Bin(char, Box<Node>, Box<Node>),
    F1(Func1, Box<Node>),
    F2(Func2, Box<Node>, Box<Node>),
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Func1 {
    Exp,
    Log,
    Sqrt,
    Abs,
    Sin,
    Cos,
    Tanh,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Func2 {
    Pow,
    Min,
    Max,
}

struct Parser<'a> {
    src: &'a str,
    chars: Vec<char>,
    pos: usize,
    names: &'a [&'a str],
    /// Current nesting (see [`MAX_EXPR_NESTING`]).
    depth: usize,
    /// Nodes built so far (see [`MAX_EXPR_NODES`]).
    nodes: usize,
}

impl Expr {
    /// Parses `src`; `names` are the parameter names it may use (in the order in which
    /// [`Expr::eval`] receives their values).
    pub fn parse(src: &str, names: &[&str]) -> Result<Self, FilterError> {
        let mut p = Parser {
            src,
            chars: src.chars().collect(),
            pos: 0,
            names,
            depth: 0,
            nodes: 0,
        };
        p.skip_ws();
        if p.pos >= p.chars.len() {
            return Err(p.err("empty expression"));
        }
        let node = p.expr()?;
        p.skip_ws();
        if p.pos < p.chars.len() {
            return Err(p.err(&format!("unexpected '{}'", p.chars[p.pos])));
        }
        Ok(Expr { node })
    }

    /// Evaluates at `s` with the parameter values in the order of the names given to
    /// [`Expr::parse`].
    pub fn eval(&self, s: f64, params: &[f64]) -> f64 {
        eval_node(&self.node, s, params)
    }
}

fn eval_node(n: &Node, s: f64, p: &[f64]) -> f64 {
    match n {
        Node::Num(v) => *v,
        Node::S => s,
        Node::Param(i) => p.get(*i).copied().unwrap_or(f64::NAN),
        Node::Neg(a) => -eval_node(a, s, p),
        Node::Bin(op, a, b) => {
            let (x, y) = (eval_node(a, s, p), eval_node(b, s, p));
            match op {
                '+' => x + y,
                '-' => x - y,
                '*' => x * y,
                '/' => x / y,
                _ => x.powf(y),
            }
        }
        Node::F1(f, a) => {
            let x = eval_node(a, s, p);
            match f {
                Func1::Exp => x.exp(),
                Func1::Log => x.ln(),
                Func1::Sqrt => x.sqrt(),
                Func1::Abs => x.abs(),
                Func1::Sin => x.sin(),
                Func1::Cos => x.cos(),
                Func1::Tanh => x.tanh(),
            }
        }
        Node::F2(f, a, b) => {
            let (x, y) = (eval_node(a, s, p), eval_node(b, s, p));
            match f {
                Func2::Pow => x.powf(y),
                Func2::Min => x.min(y),
                Func2::Max => x.max(y),
            }
        }
    }
}

impl Parser<'_> {
    fn err(&self, m: &str) -> FilterError {
        FilterError::Expression {
            expr: self.src.to_string(),
            position: self.pos,
            message: m.to_string(),
        }
    }

    /// Counts one more node, refusing expressions with more than [`MAX_EXPR_NODES`].
    fn node(&mut self, n: Node) -> Result<Node, FilterError> {
        self.nodes += 1;
        if self.nodes > MAX_EXPR_NODES {
            return Err(self.err(&format!(
                "expression too long: more than {MAX_EXPR_NODES} numbers, names and operations"
            )));
        }
        Ok(n)
    }

    /// Enters one nesting level, refusing more than [`MAX_EXPR_NESTING`].
    fn enter(&mut self) -> Result<(), FilterError> {
        self.depth += 1;
        if self.depth > MAX_EXPR_NESTING {
            return Err(self.err(&format!(
                "expression nested too deeply: more than {MAX_EXPR_NESTING} levels of parentheses, calls, signs and powers"
            )));
        }
        Ok(())
    }

    fn skip_ws(&mut self) {
        while self.pos < self.chars.len() && self.chars[self.pos].is_whitespace() {
            self.pos += 1;
        }
    }

    fn peek(&mut self) -> Option<char> {
        self.skip_ws();
        self.chars.get(self.pos).copied()
    }

    fn expect(&mut self, c: char) -> Result<(), FilterError> {
        if self.peek() == Some(c) {
            self.pos += 1;
            Ok(())
        } else {
            Err(self.err(&format!("expected '{c}'")))
        }
    }

    fn expr(&mut self) -> Result<Node, FilterError> {
        self.enter()?;
        let mut a = self.term()?;
        while let Some(c @ ('+' | '-')) = self.peek() {
            self.pos += 1;
            let b = self.term()?;
            a = self.node(Node::Bin(c, Box::new(a), Box::new(b)))?;
        }
        self.depth -= 1;
        Ok(a)
    }

    fn term(&mut self) -> Result<Node, FilterError> {
        let mut a = self.unary()?;
        while let Some(c @ ('*' | '/')) = self.peek() {
            self.pos += 1;
            let b = self.unary()?;
            a = self.node(Node::Bin(c, Box::new(a), Box::new(b)))?;
        }
        Ok(a)
    }

    fn unary(&mut self) -> Result<Node, FilterError> {
        match self.peek() {
            Some(c @ ('-' | '+')) => {
                self.pos += 1;
                self.enter()?;
                let a = self.unary()?;
                self.depth -= 1;
                if c == '-' {
                    self.node(Node::Neg(Box::new(a)))
                } else {
                    Ok(a)
                }
            }
            _ => self.power(),
        }
    }

    fn power(&mut self) -> Result<Node, FilterError> {
        let base = self.primary()?;
        if self.peek() == Some('^') {
            self.pos += 1;
            self.enter()?;
            let e = self.unary()?;
            self.depth -= 1;
            return self.node(Node::Bin('^', Box::new(base), Box::new(e)));
        }
        Ok(base)
    }

    fn primary(&mut self) -> Result<Node, FilterError> {
        let Some(c) = self.peek() else {
            return Err(self.err("unexpected end of expression"));
        };
        if c == '(' {
            self.pos += 1;
            let e = self.expr()?;
            self.expect(')')?;
            return Ok(e);
        }
        if c.is_ascii_digit() || c == '.' {
            return self.number();
        }
        if c.is_ascii_alphabetic() || c == '_' {
            let start = self.pos;
            while self.pos < self.chars.len()
                && (self.chars[self.pos].is_ascii_alphanumeric() || self.chars[self.pos] == '_')
            {
                self.pos += 1;
            }
            let name: String = self.chars[start..self.pos].iter().collect();
            if self.peek() == Some('(') {
                return self.call(&name, start);
            }
            if name == "s" {
                return self.node(Node::S);
            }
            if name == "pi" {
                return self.node(Node::Num(std::f64::consts::PI));
            }
            if let Some(i) = self.names.iter().position(|n| *n == name) {
                return self.node(Node::Param(i));
            }
            self.pos = start;
            return Err(self.err(&format!(
                "unknown name '{name}' (use s, pi or a parameter given after ';')"
            )));
        }
        Err(self.err(&format!("unexpected '{c}'")))
    }

    fn number(&mut self) -> Result<Node, FilterError> {
        let start = self.pos;
        let n = self.chars.len();
        while self.pos < n && (self.chars[self.pos].is_ascii_digit() || self.chars[self.pos] == '.')
        {
            self.pos += 1;
        }
        if self.pos < n && matches!(self.chars[self.pos], 'e' | 'E') {
            let mut q = self.pos + 1;
            if q < n && matches!(self.chars[q], '+' | '-') {
                q += 1;
            }
            if q < n && self.chars[q].is_ascii_digit() {
                while q < n && self.chars[q].is_ascii_digit() {
                    q += 1;
                }
                self.pos = q;
            }
        }
        let text: String = self.chars[start..self.pos].iter().collect();
        let v = text.parse::<f64>().map_err(|_| {
            self.pos = start;
            self.err(&format!("invalid number '{text}'"))
        })?;
        self.node(Node::Num(v))
    }

    fn call(&mut self, name: &str, start: usize) -> Result<Node, FilterError> {
        let f1 = match name {
            "exp" => Some(Func1::Exp),
            "log" | "ln" => Some(Func1::Log),
            "sqrt" => Some(Func1::Sqrt),
            "abs" => Some(Func1::Abs),
            "sin" => Some(Func1::Sin),
            "cos" => Some(Func1::Cos),
            "tanh" => Some(Func1::Tanh),
            _ => None,
        };
        let f2 = match name {
            "pow" => Some(Func2::Pow),
            "min" => Some(Func2::Min),
            "max" => Some(Func2::Max),
            _ => None,
        };
        if f1.is_none() && f2.is_none() {
            self.pos = start;
            return Err(self.err(&format!(
                "unknown function '{name}' (known: exp log sqrt abs sin cos tanh pow min max)"
            )));
        }
        self.expect('(')?;
        let a = self.expr()?;
        if let Some(f) = f1 {
            self.expect(')')?;
            return self.node(Node::F1(f, Box::new(a)));
        }
        self.expect(',')?;
        let b = self.expr()?;
        self.expect(')')?;
        match f2 {
            Some(f) => self.node(Node::F2(f, Box::new(a), Box::new(b))),
            None => Err(self.err("internal: no function")),
        }
    }
}
