//! Spectral filters: the weight `w = 1/phi` applied to the Laplacian eigenvalues.
//!
//! Convention (`docs/MATH.md`, "Filters"): a filter is stored and evaluated
//! as its **weight** `w(s) = 1/phi(s)`, so that
//!
//! ```text
//! d(p,q)^2 = sum_{k: lambda_k > 0} w(lambda_k) (x_k(p) - x_k(q))^2
//! ```
//!
//! | filter | weight `w(s)` | `phi(s) = 1/w(s)` |
//! | --- | --- | --- |
//! | [`Filter::Diffusion`] | `exp(-t s)` | `exp(t s)` |
//! | [`Filter::CommuteTime`] | `1/s` | `s` |
//! | [`Filter::Biharmonic`] | `1/s^2` | `s^2` |
//! | [`Filter::Mix`] | `(1-a) exp(-t s) + a / s^2` | its inverse |
//! | [`Filter::Polynomial`] | `s^-p` | `s^p` |
//! | [`Filter::BandSuppression`] | `|prod_{i in I} (s - lambda_i)|`, exactly 0 at `i in I` | `1/|prod ...|` |
//! | [`Filter::Custom`] | the expression (kind `Weight`) or its inverse (kind `Phi`) | |
//!
//! Zero eigenvalues (one per connected component) are skipped: an eigenvalue with
//! `lambda <= ZERO_EIGENVALUE_EPS * lambda_max` (in absolute value) counts as zero and gets
//! weight 0 in [`Filter::weights`]. Every other eigenvalue must receive a strictly positive,
//! finite weight, or [`Filter::weights`] refuses the filter, naming the first failing pair.
//!
//! The band-suppression filter of the paper, `phi(s) = [prod_{i in I}(s - lambda_i)]^-1`, is
//! negative between suppressed eigenvalues; we make it positive by taking the absolute
//! value, `w(s) = |prod_{i in I}(s - lambda_i)|`. The suppressed pairs `i in I` get weight
//! exactly 0 (that is the point of the filter: their eigenvectors do not contribute); any
//! *other* pair whose eigenvalue coincides with a suppressed one gets weight 0 too and is
//! refused as not strictly positive.
//!
//! # Text syntax ([`Filter::from_str`])
//!
//! - `diffusion:t=0.5` (also `heat:t=0.5`; `t` defaults to 0.5)
//! - `commute` (also `commute-time`)
//! - `biharmonic` (also `bi-harmonic`)
//! - `mix:a=0.5,t=0.5` (defaults `a = 0.5`, `t = 0.5`)
//! - `poly:p=2` (also `polynomial:p=2`)
//! - `band:1,4,5` (band suppression of eigenpairs 1, 4 and 5; 0-based, as in the basis)
//! - `custom-w:EXPR;name=value,...`: EXPR is the **weight** `w(s)`
//! - `custom-phi:EXPR;name=value,...`: EXPR is the **filter map** `phi(s)`; `w = 1/phi`
//!
//! Expressions: numbers (`1`, `2.5`, `1e-3`), the variable `s`, the constant `pi`, named
//! parameters, `+ - * / ^` (`^` binds tightest and is right-associative, `-s^2 = -(s^2)`),
//! unary minus, parentheses, and the functions `exp log sqrt abs sin cos tanh` (one
//! argument) and `pow min max` (two arguments). Example: `custom-w:exp(-s*t)/s;t=0.1`.
//! An expression may nest parentheses, function calls, signs and powers at most
//! [`MAX_EXPR_NESTING`] deep and hold at most [`MAX_EXPR_NODES`] numbers, names and
//! operations, so that parsing, evaluating and dropping it never overflow a thread's stack
//! (a server's worker threads have 2 MB).

use std::collections::BTreeMap;
use std::fmt;
use std::str::FromStr;

/// Eigenvalues with `|lambda| <= ZERO_EIGENVALUE_EPS * lambda_max` count as zero (one per
/// connected component) and are skipped. The value matches pyFM's WKS cut-off.
pub const ZERO_EIGENVALUE_EPS: f64 = 1e-8;

/// Deepest nesting of parentheses, function calls, unary signs and powers in a custom
/// expression.
pub const MAX_EXPR_NESTING: usize = 64;

/// Most numbers, names and operations in a custom expression.
pub const MAX_EXPR_NODES: usize = 1000;

/// Errors of filters: validation on a spectrum and parsing.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum FilterError {
    /// The weight is not strictly positive and finite at an eigenvalue that is used.
    #[error(
        "filter {filter} is not strictly positive and finite on the spectrum: w({value}) = {weight} at eigenpair index {index}"
    )]
    NotPositive {
        /// The filter, as text.
        filter: String,
        /// Index of the first failing eigenpair (0-based, in the basis).
        index: usize,
        /// Its eigenvalue.
        value: f64,
        /// The weight computed there.
        weight: f64,
    },
    /// A parameter is out of its domain (e.g. `t <= 0`, `a` outside `[0, 1]`).
    #[error("invalid filter parameter: {0}")]
    InvalidParameter(String),
    /// A band-suppression index is not in the basis.
    #[error("band-suppression index {index} is out of range: the basis has {k} eigenpairs")]
    IndexOutOfRange {
        /// The offending index.
        index: usize,
        /// Number of pairs in the basis.
        k: usize,
    },
    /// The spectrum is empty or has only zero eigenvalues.
    #[error(
        "the spectrum has no non-zero eigenvalue to filter: every pair computed is a zero one (a shape with c separate pieces has c zero eigenvalues; ask for more than c pairs)"
    )]
    EmptySpectrum,
    /// The filter text could not be parsed.
    #[error("cannot parse filter '{text}': {message}")]
    Syntax {
        /// The text given.
        text: String,
        /// What is wrong.
        message: String,
    },
    /// A custom expression could not be parsed.
    #[error("expression error at character {position} of '{expr}': {message}")]
    Expression {
        /// The expression.
        expr: String,
        /// 0-based character position.
        position: usize,
        /// What is wrong.
        message: String,
    },
}

/// Whether a custom expression is the weight `w(s)` or the filter map `phi(s) = 1/w(s)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CustomKind {
    /// The expression is the weight `w(s)`.
    Weight,
    /// The expression is the paper's filter map `phi(s)`; the weight is `1/phi(s)`.
    Phi,
}

/// A spectral filter, stored as its weight `w = 1/phi` (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub enum Filter {
    /// Diffusion distance at time `t`: `w(s) = exp(-t s)`.
    Diffusion {
        /// Diffusion time, `> 0`.
        t: f64,
    },
    /// Commute-time distance: `w(s) = 1/s`.
    CommuteTime,
    /// Bi-harmonic distance: `w(s) = 1/s^2`.
    Biharmonic,
    /// The paper's mix (Fig. 14) read as weights: `w(s) = (1-a) exp(-t s) + a/s^2`.
    Mix {
        /// Blend, in `[0, 1]`: 0 = diffusion, 1 = bi-harmonic.
        a: f64,
        /// Diffusion time, `> 0` (unused when `a = 1`).
        t: f64,
    },
    /// `phi(s) = s^p`, `w(s) = s^-p`.
    Polynomial {
        /// Exponent.
        p: f64,
    },
    /// Suppresses the listed eigenpairs: `w(s) = |prod_{i} (s - lambda_i)|`, 0 at the
    /// listed pairs. Needs the spectrum, so [`Filter::weight`] returns NaN for it; use
    /// [`Filter::weights`].
    BandSuppression {
        /// 0-based eigenpair indices to suppress.
        indices: Vec<usize>,
    },
    /// A user expression in `s` and named parameters (see the module documentation).
    Custom {
        /// The expression text.
        expr: String,
        /// Named parameters the expression may use.
        params: BTreeMap<String, f64>,
        /// Whether `expr` is the weight or the filter map `phi`.
        kind: CustomKind,
    },
}

impl Default for Filter {
    /// The executable paper's default distance: bi-harmonic.
    fn default() -> Self {
        Filter::Biharmonic
    }
}

impl Filter {
    /// A custom filter, checking that the expression parses with the given parameters.
    pub fn custom(
        expr: &str,
        params: BTreeMap<String, f64>,
        kind: CustomKind,
    ) -> Result<Self, FilterError> {
        let names: Vec<&str> = params.keys().map(String::as_str).collect();
        Expr::parse(expr, &names)?;
        Ok(Filter::Custom {
            expr: expr.to_string(),
            params,
            kind,
        })
    }

    /// The weight `w(s) = 1/phi(s)` at one value `s`. No validation: may be negative,
    /// infinite or NaN (e.g. `1/s` at 0, an unparsable custom expression, or
    /// [`Filter::BandSuppression`], which needs the spectrum).
    pub fn weight(&self, s: f64) -> f64 {
        match self.evaluator() {
            Ok(ev) => ev.eval(s, &[]),
            Err(_) => f64::NAN,
        }
    }

    fn evaluator(&self) -> Result<Evaluator<'_>, FilterError> {
        Ok(match self {
            Filter::Custom { expr, params, kind } => {
                let names: Vec<&str> = params.keys().map(String::as_str).collect();
                let e = Expr::parse(expr, &names)?;
                Evaluator::Custom {
                    e,
                    values: params.values().copied().collect(),
                    kind: *kind,
                }
            }
            f => Evaluator::Builtin(f),
        })
    }

    /// Checks the parameters of the built-in filters.
    pub fn validate_parameters(&self) -> Result<(), FilterError> {
        let bad = |m: String| Err(FilterError::InvalidParameter(m));
        match *self {
            Filter::Diffusion { t } if !(t.is_finite() && t > 0.0) => {
                bad(format!("diffusion time t must be finite and > 0, got {t}"))
            }
            Filter::Mix { a, t } => {
                if !(0.0..=1.0).contains(&a) {
                    bad(format!("mix blend a must be in [0, 1], got {a}"))
                } else if !(t.is_finite() && t > 0.0) {
                    bad(format!("mix time t must be finite and > 0, got {t}"))
                } else {
                    Ok(())
                }
            }
            Filter::Polynomial { p } if !p.is_finite() => {
                bad(format!("polynomial exponent p must be finite, got {p}"))
            }
            _ => Ok(()),
        }
    }

    /// Weights of the spectrum `eigenvalues` (`k` entries, one per pair).
    ///
    /// Zero eigenvalues (`|lambda| <= ZERO_EIGENVALUE_EPS * lambda_max`) get weight 0 (they
    /// are skipped), as do the suppressed pairs of [`Filter::BandSuppression`]. Every other
    /// weight must be strictly positive and finite, or the filter is refused with
    /// [`FilterError::NotPositive`] naming the first failing pair.
    pub fn weights(&self, eigenvalues: &[f64]) -> Result<Vec<f64>, FilterError> {
        self.validate_parameters()?;
        let lmax = eigenvalues.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if !lmax.is_finite() || lmax <= 0.0 {
            return Err(FilterError::EmptySpectrum);
        }
        let zero = |v: f64| v.abs() <= ZERO_EIGENVALUE_EPS * lmax;
        let mut suppressed = vec![false; eigenvalues.len()];
        let mut band: Vec<f64> = Vec::new();
        if let Filter::BandSuppression { indices } = self {
            for &i in indices {
                if i >= eigenvalues.len() {
                    return Err(FilterError::IndexOutOfRange {
                        index: i,
                        k: eigenvalues.len(),
                    });
                }
                suppressed[i] = true;
                band.push(eigenvalues[i]);
            }
        }
        let ev = self.evaluator()?;
        let mut out = Vec::with_capacity(eigenvalues.len());
        let mut any = false;
        for (i, &l) in eigenvalues.iter().enumerate() {
            if zero(l) || suppressed[i] {
                out.push(0.0);
                continue;
            }
            let w = ev.eval(l, &band);
            if !(w.is_finite() && w > 0.0) {
                return Err(FilterError::NotPositive {
                    filter: self.to_string(),
                    index: i,
                    value: l,
                    weight: w,
                });
            }
            any = true;
            out.push(w);
        }
        if !any {
            return Err(FilterError::EmptySpectrum);
        }
        Ok(out)
    }
}

enum Evaluator<'a> {
    Builtin(&'a Filter),
    Custom {
        e: Expr,
        values: Vec<f64>,
        kind: CustomKind,
    },
}

impl Evaluator<'_> {
    fn eval(&self, s: f64, band: &[f64]) -> f64 {
        match self {
            Evaluator::Builtin(f) => match **f {
                Filter::Diffusion { t } => (-t * s).exp(),
                Filter::CommuteTime => 1.0 / s,
                Filter::Biharmonic => 1.0 / (s * s),
                Filter::Mix { a, t } => (1.0 - a) * (-t * s).exp() + a / (s * s),
                Filter::Polynomial { p } => s.powf(-p),
                Filter::BandSuppression { .. } => {
                    if band.is_empty() {
                        f64::NAN
                    } else {
                        band.iter().map(|l| s - l).product::<f64>().abs()
                    }
                }
                Filter::Custom { .. } => f64::NAN,
            },
            Evaluator::Custom { e, values, kind } => {
                let v = e.eval(s, values);
                match kind {
                    CustomKind::Weight => v,
                    CustomKind::Phi => 1.0 / v,
                }
            }
        }
    }
}

impl fmt::Display for Filter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Filter::Diffusion { t } => write!(f, "diffusion:t={t}"),
            Filter::CommuteTime => f.write_str("commute"),
            Filter::Biharmonic => f.write_str("biharmonic"),
            Filter::Mix { a, t } => write!(f, "mix:a={a},t={t}"),
            Filter::Polynomial { p } => write!(f, "poly:p={p}"),
            Filter::BandSuppression { indices } => {
                let v: Vec<String> = indices.iter().map(|i| i.to_string()).collect();
                write!(f, "band:{}", v.join(","))
            }
            Filter::Custom { expr, params, kind } => {
                let k = match kind {
                    CustomKind::Weight => "custom-w",
                    CustomKind::Phi => "custom-phi",
                };
                write!(f, "{k}:{expr}")?;
                if !params.is_empty() {
                    let v: Vec<String> = params.iter().map(|(n, x)| format!("{n}={x}")).collect();
                    write!(f, ";{}", v.join(","))?;
                }
                Ok(())
            }
        }
    }
}

fn parse_params(text: &str, list: &str) -> Result<BTreeMap<String, f64>, FilterError> {
    let mut m = BTreeMap::new();
    for item in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let (k, v) = item.split_once('=').ok_or_else(|| FilterError::Syntax {
            text: text.to_string(),
            message: format!("parameter '{item}' is not of the form name=value"),
        })?;
        let k = k.trim();
        let valid = k
            .chars()
            .next()
            .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
            && k.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
        if !valid || k == "s" || k == "pi" {
            return Err(FilterError::Syntax {
                text: text.to_string(),
                message: format!("'{k}' is not a valid parameter name"),
            });
        }
        let x: f64 = v.trim().parse().map_err(|_| FilterError::Syntax {
            text: text.to_string(),
            message: format!("value of '{k}' is not a number: '{}'", v.trim()),
        })?;
        if m.insert(k.to_string(), x).is_some() {
            return Err(FilterError::Syntax {
                text: text.to_string(),
                message: format!("parameter '{k}' given twice"),
            });
        }
    }
    Ok(m)
}

impl FromStr for Filter {
    type Err = FilterError;

    /// Parses the syntax of the module documentation.
    fn from_str(text: &str) -> Result<Self, FilterError> {
        let t = text.trim();
        let (name, rest) = match t.split_once(':') {
            Some((a, b)) => (a.trim().to_ascii_lowercase(), b.trim()),
            None => (t.to_ascii_lowercase(), ""),
        };
        let syntax = |m: String| FilterError::Syntax {
            text: text.to_string(),
            message: m,
        };
        let named = |allowed: &[&str]| -> Result<BTreeMap<String, f64>, FilterError> {
            let p = parse_params(text, rest)?;
            if let Some(k) = p.keys().find(|k| !allowed.contains(&k.as_str())) {
                return Err(syntax(format!(
                    "unknown parameter '{k}' for '{name}' (expected: {})",
                    if allowed.is_empty() {
                        "none".to_string()
                    } else {
                        allowed.join(", ")
                    }
                )));
            }
            Ok(p)
        };
        let f = match name.as_str() {
            "diffusion" | "heat" => {
                let p = named(&["t"])?;
                Filter::Diffusion {
                    t: p.get("t").copied().unwrap_or(0.5),
                }
            }
            "commute" | "commute-time" | "commute_time" => {
                named(&[])?;
                Filter::CommuteTime
            }
            "biharmonic" | "bi-harmonic" => {
                named(&[])?;
                Filter::Biharmonic
            }
            "mix" => {
                let p = named(&["a", "t"])?;
                Filter::Mix {
                    a: p.get("a").copied().unwrap_or(0.5),
                    t: p.get("t").copied().unwrap_or(0.5),
                }
            }
            "poly" | "polynomial" => {
                let p = named(&["p"])?;
                Filter::Polynomial {
                    p: *p
                        .get("p")
                        .ok_or_else(|| syntax("poly needs p, e.g. poly:p=2".into()))?,
                }
            }
            "band" | "band-suppression" => {
                let mut indices = Vec::new();
                for item in rest.split(',').map(str::trim).filter(|s| !s.is_empty()) {
                    indices.push(item.parse::<usize>().map_err(|_| {
                        syntax(format!("band index '{item}' is not a non-negative integer"))
                    })?);
                }
                if indices.is_empty() {
                    return Err(syntax("band needs indices, e.g. band:1,2".into()));
                }
                Filter::BandSuppression { indices }
            }
            "custom-w" | "custom-phi" => {
                let (expr, plist) = match rest.split_once(';') {
                    Some((e, p)) => (e.trim(), p),
                    None => (rest, ""),
                };
                if expr.is_empty() {
                    return Err(syntax(format!("{name} needs an expression after ':'")));
                }
                let params = parse_params(text, plist)?;
                let kind = if name == "custom-w" {
                    CustomKind::Weight
                } else {
                    CustomKind::Phi
                };
                Filter::custom(expr, params, kind)?
            }
            _ => {
                return Err(syntax(format!(
                    "unknown filter '{name}': expected diffusion, commute, biharmonic, mix, poly, band, custom-w or custom-phi"
                )));
            }
        };
        f.validate_parameters()?;
        Ok(f)
    }
}

// ---------------------------------------------------------------------------------------
// A small safe expression language.

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

#[cfg(test)]
mod tests {
    use super::*;

    fn ev(src: &str, s: f64) -> f64 {
        Expr::parse(src, &["t"]).unwrap().eval(s, &[0.5])
    }

    #[test]
    fn expression_precedence_and_functions() {
        assert_eq!(ev("1 + 2 * 3", 0.0), 7.0);
        assert_eq!(ev("-s^2", 3.0), -9.0);
        assert_eq!(ev("2^3^2", 0.0), 512.0);
        assert_eq!(ev("(1+2)*3", 0.0), 9.0);
        assert_eq!(ev("2*-s", 3.0), -6.0);
        assert!((ev("exp(-s*t)/s", 2.0) - (-1.0f64).exp() / 2.0).abs() < 1e-15);
        assert_eq!(ev("max(s, 1) + min(s, 1) + pow(2, 3)", 4.0), 13.0);
        assert_eq!(ev("1e-3 * 1E3", 0.0), 1.0);
        assert!(
            (ev(
                "sqrt(abs(-4)) + log(exp(1)) + tanh(0) + sin(0) + cos(0)",
                0.0
            ) - 4.0)
                .abs()
                < 1e-15
        );
    }

    #[test]
    fn parse_errors_give_positions() {
        let e = Expr::parse("s + * 2", &[]).unwrap_err();
        assert!(
            matches!(e, FilterError::Expression { position: 4, .. }),
            "{e}"
        );
        let e = Expr::parse("exp(s", &[]).unwrap_err();
        assert!(
            matches!(e, FilterError::Expression { position: 5, .. }),
            "{e}"
        );
        let e = Expr::parse("foo(s)", &[]).unwrap_err();
        assert!(e.to_string().contains("unknown function 'foo'"), "{e}");
        let e = Expr::parse("s * q", &[]).unwrap_err();
        assert!(
            matches!(e, FilterError::Expression { position: 4, .. }),
            "{e}"
        );
        assert!(Expr::parse("", &[]).is_err());
        assert!(Expr::parse("(s))", &[]).is_err());
        assert!(Expr::parse("pow(s)", &[]).is_err());
    }

    #[test]
    fn nesting_and_size_limits() {
        let nested = |d: usize| format!("{}s{}", "(".repeat(d), ")".repeat(d));
        // expr() itself is one level, each parenthesis one more.
        assert!(Expr::parse(&nested(MAX_EXPR_NESTING - 1), &[]).is_ok());
        let e = Expr::parse(&nested(MAX_EXPR_NESTING), &[]).unwrap_err();
        assert!(e.to_string().contains("nested too deeply"), "{e}");
        let e = Expr::parse(&format!("{}s", "-".repeat(100)), &[]).unwrap_err();
        assert!(e.to_string().contains("nested too deeply"), "{e}");
        // n terms make 2n - 1 nodes.
        let sum = |n: usize| vec!["s"; n].join("+");
        assert!(Expr::parse(&sum(MAX_EXPR_NODES.div_ceil(2)), &[]).is_ok());
        let e = Expr::parse(&sum(MAX_EXPR_NODES.div_ceil(2) + 1), &[]).unwrap_err();
        assert!(e.to_string().contains("expression too long"), "{e}");
        assert!(format!("custom-w:{}", sum(2000)).parse::<Filter>().is_err());
    }

    #[test]
    fn filter_text_round_trip() {
        for t in [
            "diffusion:t=0.25",
            "commute",
            "biharmonic",
            "mix:a=0.3,t=0.7",
            "poly:p=2",
            "band:1,3",
            "custom-w:exp(-s*t)/s;t=0.1",
            "custom-phi:s^2",
        ] {
            let f: Filter = t.parse().unwrap();
            let g: Filter = f.to_string().parse().unwrap();
            assert_eq!(f, g, "{t}");
        }
        assert_eq!(
            "heat".parse::<Filter>().unwrap(),
            Filter::Diffusion { t: 0.5 }
        );
        assert!("diffusion:t=-1".parse::<Filter>().is_err());
        assert!("mix:a=2".parse::<Filter>().is_err());
        assert!("diffusion:x=1".parse::<Filter>().is_err());
        assert!("nonsense".parse::<Filter>().is_err());
        assert!("custom-w:s*q".parse::<Filter>().is_err());
        assert!("poly".parse::<Filter>().is_err());
    }

    #[test]
    fn weights_skip_zero_and_refuse_negative() {
        let ev = [1e-14, 1.0, 2.0, 3.0];
        let w = Filter::Biharmonic.weights(&ev).unwrap();
        assert_eq!(w, vec![0.0, 1.0, 0.25, 1.0 / 9.0]);
        let f: Filter = "custom-w:2 - s".parse().unwrap();
        match f.weights(&ev).unwrap_err() {
            FilterError::NotPositive { index, value, .. } => {
                assert_eq!(index, 2);
                assert_eq!(value, 2.0);
            }
            e => panic!("{e}"),
        }
        let phi: Filter = "custom-phi:s^2".parse().unwrap();
        assert_eq!(phi.weights(&ev).unwrap(), w);
        let band = Filter::BandSuppression { indices: vec![2] };
        assert_eq!(band.weights(&ev).unwrap(), vec![0.0, 1.0, 0.0, 1.0]);
        assert!(
            Filter::BandSuppression { indices: vec![9] }
                .weights(&ev)
                .is_err()
        );
        assert!(Filter::CommuteTime.weights(&[0.0, 0.0]).is_err());
    }
}
