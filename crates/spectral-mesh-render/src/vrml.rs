//! VRML 2.0 (`.wrl`) output of a [`Scene`], readable by view3dscene and similar viewers,
//! and a small parser that reads such files back into a node tree and a summary.
//!
//! The file holds: one `Shape` with an `IndexedFaceSet` (per-vertex colours,
//! `colorPerVertex TRUE`, `solid FALSE`); one black `IndexedLineSet` per non-empty level
//! set (closed polylines repeat their first index); one small `Sphere` per marker inside a
//! `Transform`, radius 0.75 % of the bounding-box diagonal, with the marker colour.

use crate::raster::Scene;
use std::fmt::Write as _;
use std::io::{self, Write};
use thiserror::Error;

/// Marker sphere radius as a fraction of the mesh's bounding-box diagonal.
pub const MARKER_RADIUS_FRACTION: f64 = 0.0075;

/// Writes `scene` as VRML 2.0.
pub fn write_vrml(w: &mut impl Write, scene: &Scene) -> io::Result<()> {
    let mesh = scene.mesh;
    let mut s = String::new();
    s.push_str("#VRML V2.0 utf8\n# written by spectral-mesh-render\n\n");
    s.push_str("Shape {\n  appearance Appearance { material Material { diffuseColor 1 1 1 } }\n");
    if scene.point_radius.is_some() {
        // A point cloud: a PointSet of the vertices in their colours.
        s.push_str("  geometry PointSet {\n");
    } else {
        s.push_str("  geometry IndexedFaceSet {\n    solid FALSE\n    colorPerVertex TRUE\n");
    }
    s.push_str("    coord Coordinate { point [\n");
    for p in mesh.positions() {
        let _ = writeln!(s, "      {} {} {},", p[0], p[1], p[2]);
    }
    s.push_str("    ] }\n    color Color { color [\n");
    for c in &scene.vertex_colors {
        let f = |v: f32| {
            if v.is_finite() {
                v.clamp(0.0, 1.0)
            } else {
                0.5
            }
        };
        let _ = writeln!(s, "      {:.4} {:.4} {:.4},", f(c[0]), f(c[1]), f(c[2]));
    }
    if scene.point_radius.is_some() {
        s.push_str("    ] }\n  }\n}\n");
    } else {
        s.push_str("    ] }\n    coordIndex [\n");
        for t in mesh.triangles() {
            let _ = writeln!(s, "      {} {} {} -1,", t[0], t[1], t[2]);
        }
        s.push_str("    ]\n  }\n}\n");
    }
    w.write_all(s.as_bytes())?;

    for ls in &scene.level_sets {
        if ls.polylines.is_empty() {
            continue;
        }
        let mut s = String::new();
        let _ = writeln!(s, "\n# level set {}", ls.value);
        s.push_str("Shape {\n  appearance Appearance { material Material { diffuseColor 0 0 0 emissiveColor 0 0 0 } }\n");
        s.push_str("  geometry IndexedLineSet {\n    coord Coordinate { point [\n");
        for pl in &ls.polylines {
            for p in &pl.points {
                let _ = writeln!(s, "      {} {} {},", p[0], p[1], p[2]);
            }
        }
        s.push_str("    ] }\n    coordIndex [\n");
        let mut base = 0usize;
        for pl in &ls.polylines {
            let n = pl.points.len();
            s.push_str("     ");
            for i in 0..n {
                let _ = write!(s, " {}", base + i);
            }
            if pl.closed && n > 0 {
                let _ = write!(s, " {base}");
            }
            s.push_str(" -1,\n");
            base += n;
        }
        s.push_str("    ]\n  }\n}\n");
        w.write_all(s.as_bytes())?;
    }

    let radius = MARKER_RADIUS_FRACTION * mesh.diagonal().max(f64::MIN_POSITIVE);
    for m in &scene.markers {
        let c = m.kind.color();
        let p = m.position;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "\nTransform {{\n  translation {} {} {}\n  children [ Shape {{\n    appearance Appearance {{ material Material {{ diffuseColor {:.4} {:.4} {:.4} }} }}\n    geometry Sphere {{ radius {} }}\n  }} ]\n}}",
            p[0],
            p[1],
            p[2],
            f32::from(c[0]) / 255.0,
            f32::from(c[1]) / 255.0,
            f32::from(c[2]) / 255.0,
            radius
        );
        w.write_all(s.as_bytes())?;
    }
    Ok(())
}

/// Errors of the VRML parser.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum VrmlError {
    /// The `#VRML V2.0` header is missing.
    #[error("missing '#VRML V2.0' header")]
    Header,
    /// Unexpected token or end of input.
    #[error("line {line}: {message}")]
    Syntax {
        /// 1-based line.
        line: usize,
        /// What went wrong.
        message: String,
    },
}

/// A parsed field value.
#[derive(Debug, Clone, PartialEq)]
pub enum VrmlValue {
    /// A single node (`SFNode`), or `NULL` as `None`.
    Node(Option<Box<VrmlNode>>),
    /// A bracketed list of nodes (`MFNode`).
    Nodes(Vec<VrmlNode>),
    /// Numbers, bracketed or not (`SFVec3f`, `MFInt32`, ...).
    Numbers(Vec<f64>),
    /// Anything else (booleans, strings, identifiers).
    Words(Vec<String>),
}

/// A parsed node: its type and fields, in file order.
#[derive(Debug, Clone, PartialEq)]
pub struct VrmlNode {
    /// Node type, e.g. `IndexedFaceSet`.
    pub kind: String,
    /// `(field name, value)` pairs.
    pub fields: Vec<(String, VrmlValue)>,
}

impl VrmlNode {
    /// The first field called `name`.
    pub fn field(&self, name: &str) -> Option<&VrmlValue> {
        self.fields.iter().find(|(n, _)| n == name).map(|(_, v)| v)
    }

    /// The node held by field `name`, if any.
    pub fn child(&self, name: &str) -> Option<&VrmlNode> {
        match self.field(name) {
            Some(VrmlValue::Node(Some(n))) => Some(n),
            _ => None,
        }
    }

    /// The numbers held by field `name` (empty if absent).
    pub fn numbers(&self, name: &str) -> &[f64] {
        match self.field(name) {
            Some(VrmlValue::Numbers(v)) => v,
            _ => &[],
        }
    }

    fn visit<'a>(&'a self, f: &mut impl FnMut(&'a VrmlNode)) {
        f(self);
        for (_, v) in &self.fields {
            match v {
                VrmlValue::Node(Some(n)) => n.visit(f),
                VrmlValue::Nodes(ns) => ns.iter().for_each(|n| n.visit(f)),
                _ => {}
            }
        }
    }
}

/// Counts read back from a VRML file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct VrmlSummary {
    /// Points of the `IndexedFaceSet` coordinates (all face sets).
    pub n_points: usize,
    /// Faces of the `IndexedFaceSet`s (index runs ended by `-1` or the end).
    pub n_faces: usize,
    /// Colours of the `IndexedFaceSet`s.
    pub n_colors: usize,
    /// Number of `IndexedLineSet` nodes.
    pub n_line_sets: usize,
    /// Points of the `IndexedLineSet` coordinates.
    pub n_line_points: usize,
    /// Number of `Sphere` nodes.
    pub n_spheres: usize,
}

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Open,
    Close,
    LBracket,
    RBracket,
    Num(f64),
    Word(String),
    Str(String),
}

fn tokenize(text: &str) -> Vec<(Tok, usize)> {
    let mut out = Vec::new();
    let mut line = 1;
    let mut it = text.chars().peekable();
    while let Some(&c) = it.peek() {
        match c {
            '\n' => {
                line += 1;
                it.next();
            }
            c if c.is_whitespace() || c == ',' => {
                it.next();
            }
            '#' => {
                while let Some(&c) = it.peek() {
                    if c == '\n' {
                        break;
                    }
                    it.next();
                }
            }
            '{' | '}' | '[' | ']' => {
                it.next();
                out.push((
                    match c {
                        '{' => Tok::Open,
                        '}' => Tok::Close,
                        '[' => Tok::LBracket,
                        _ => Tok::RBracket,
                    },
                    line,
                ));
            }
            '"' => {
                it.next();
                let mut s = String::new();
                while let Some(c) = it.next() {
                    match c {
                        '"' => break,
                        '\\' => {
                            if let Some(d) = it.next() {
                                s.push(d);
                            }
                        }
                        '\n' => {
                            line += 1;
                            s.push(c);
                        }
                        _ => s.push(c),
                    }
                }
                out.push((Tok::Str(s), line));
            }
            _ => {
                let mut s = String::new();
                while let Some(&c) = it.peek() {
                    if c.is_whitespace() || matches!(c, ',' | '{' | '}' | '[' | ']' | '#' | '"') {
                        break;
                    }
                    s.push(c);
                    it.next();
                }
                let tok = match s.parse::<f64>() {
                    Ok(v) if s.starts_with(|c: char| c.is_ascii_digit() || "+-.".contains(c)) => {
                        Tok::Num(v)
                    }
                    _ => Tok::Word(s),
                };
                out.push((tok, line));
            }
        }
    }
    out
}

struct Parser {
    toks: Vec<(Tok, usize)>,
    pos: usize,
}

impl Parser {
    fn peek(&self) -> Option<&Tok> {
        self.toks.get(self.pos).map(|(t, _)| t)
    }
    fn peek2(&self) -> Option<&Tok> {
        self.toks.get(self.pos + 1).map(|(t, _)| t)
    }
    fn line(&self) -> usize {
        self.toks
            .get(self.pos.min(self.toks.len().saturating_sub(1)))
            .map_or(0, |(_, l)| *l)
    }
    fn err(&self, m: &str) -> VrmlError {
        VrmlError::Syntax {
            line: self.line(),
            message: m.to_string(),
        }
    }
    fn next(&mut self) -> Option<Tok> {
        let t = self.toks.get(self.pos).map(|(t, _)| t.clone());
        self.pos += 1;
        t
    }

    /// Whether a node starts here: `Type {`, `DEF name Type {` or `USE name`.
    fn at_node(&self) -> bool {
        match (self.peek(), self.peek2()) {
            (Some(Tok::Word(w)), _) if w == "DEF" || w == "USE" => true,
            (Some(Tok::Word(_)), Some(Tok::Open)) => true,
            _ => false,
        }
    }

    fn node(&mut self, depth: usize) -> Result<VrmlNode, VrmlError> {
        if depth > 200 {
            return Err(self.err("nesting too deep"));
        }
        match self.next() {
            Some(Tok::Word(w)) if w == "DEF" => {
                match self.next() {
                    Some(Tok::Word(_)) => {}
                    _ => return Err(self.err("expected a name after DEF")),
                }
                self.node(depth)
            }
            Some(Tok::Word(w)) if w == "USE" => match self.next() {
                Some(Tok::Word(name)) => Ok(VrmlNode {
                    kind: "USE".to_string(),
                    fields: vec![("name".to_string(), VrmlValue::Words(vec![name]))],
                }),
                _ => Err(self.err("expected a name after USE")),
            },
            Some(Tok::Word(kind)) => {
                if self.next() != Some(Tok::Open) {
                    return Err(self.err("expected '{'"));
                }
                let mut fields = Vec::new();
                loop {
                    match self.next() {
                        Some(Tok::Close) => break,
                        Some(Tok::Word(name)) => {
                            if name == "ROUTE" || name == "PROTO" || name == "EXTERNPROTO" {
                                return Err(self.err("PROTO and ROUTE are not supported"));
                            }
                            let v = self.value(depth)?;
                            fields.push((name, v));
                        }
                        None => return Err(self.err("unexpected end of file inside a node")),
                        Some(t) => return Err(self.err(&format!("unexpected {t:?} in {kind}"))),
                    }
                }
                Ok(VrmlNode { kind, fields })
            }
            _ => Err(self.err("expected a node")),
        }
    }

    fn value(&mut self, depth: usize) -> Result<VrmlValue, VrmlError> {
        if self.at_node() {
            return Ok(VrmlValue::Node(Some(Box::new(self.node(depth + 1)?))));
        }
        match self.peek() {
            Some(Tok::Word(w)) if w == "NULL" => {
                self.pos += 1;
                Ok(VrmlValue::Node(None))
            }
            Some(Tok::LBracket) => {
                self.pos += 1;
                let mut nums = Vec::new();
                let mut nodes = Vec::new();
                let mut words = Vec::new();
                loop {
                    if self.at_node() {
                        nodes.push(self.node(depth + 1)?);
                        continue;
                    }
                    match self.next() {
                        Some(Tok::RBracket) => break,
                        Some(Tok::Num(v)) => nums.push(v),
                        Some(Tok::Word(s)) | Some(Tok::Str(s)) => words.push(s),
                        None => return Err(self.err("unexpected end of file inside '['")),
                        Some(t) => return Err(self.err(&format!("unexpected {t:?} in a list"))),
                    }
                }
                let kinds = usize::from(!nums.is_empty())
                    + usize::from(!nodes.is_empty())
                    + usize::from(!words.is_empty());
                if kinds > 1 {
                    return Err(self.err("mixed list"));
                }
                Ok(if !nodes.is_empty() {
                    VrmlValue::Nodes(nodes)
                } else if !words.is_empty() {
                    VrmlValue::Words(words)
                } else {
                    VrmlValue::Numbers(nums)
                })
            }
            Some(Tok::Num(_)) => {
                let mut nums = Vec::new();
                while let Some(Tok::Num(v)) = self.peek() {
                    nums.push(*v);
                    self.pos += 1;
                }
                Ok(VrmlValue::Numbers(nums))
            }
            Some(Tok::Str(_)) | Some(Tok::Word(_)) => {
                // A single word (TRUE, FALSE) or string.
                match self.next() {
                    Some(Tok::Str(s)) | Some(Tok::Word(s)) => Ok(VrmlValue::Words(vec![s])),
                    _ => Err(self.err("expected a value")),
                }
            }
            _ => Err(self.err("expected a field value")),
        }
    }
}

/// Parses VRML 2.0 text into its top-level nodes (no PROTO or ROUTE support).
pub fn parse_vrml(text: &str) -> Result<Vec<VrmlNode>, VrmlError> {
    if !text.trim_start().starts_with("#VRML V2.0") {
        return Err(VrmlError::Header);
    }
    let mut p = Parser {
        toks: tokenize(text),
        pos: 0,
    };
    let mut nodes = Vec::new();
    while p.peek().is_some() {
        nodes.push(p.node(0)?);
    }
    Ok(nodes)
}

/// Parses VRML 2.0 text and counts what [`write_vrml`] writes (see [`VrmlSummary`]).
pub fn parse_vrml_summary(text: &str) -> Result<VrmlSummary, VrmlError> {
    let nodes = parse_vrml(text)?;
    let mut s = VrmlSummary::default();
    let points = |n: &VrmlNode, field: &str, kind: &str| {
        n.child(field)
            .filter(|c| c.kind == kind)
            .map_or(0, |c| c.numbers(field_array(kind)).len() / 3)
    };
    for root in &nodes {
        root.visit(&mut |n| match n.kind.as_str() {
            "IndexedFaceSet" => {
                s.n_points += points(n, "coord", "Coordinate");
                s.n_colors += points(n, "color", "Color");
                s.n_faces += count_runs(n.numbers("coordIndex"));
            }
            "IndexedLineSet" => {
                s.n_line_sets += 1;
                s.n_line_points += points(n, "coord", "Coordinate");
            }
            "Sphere" => s.n_spheres += 1,
            _ => {}
        });
    }
    Ok(s)
}

fn field_array(kind: &str) -> &'static str {
    if kind == "Color" { "color" } else { "point" }
}

/// Number of non-empty index runs separated by `-1`.
fn count_runs(idx: &[f64]) -> usize {
    let mut runs = 0;
    let mut len = 0;
    for &i in idx {
        if i < 0.0 {
            if len > 0 {
                runs += 1;
            }
            len = 0;
        } else {
            len += 1;
        }
    }
    if len > 0 {
        runs += 1;
    }
    runs
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parser_reads_nested_nodes_and_comments() {
        let text = "#VRML V2.0 utf8\n# comment { [ \nDEF T Transform { translation 1 2 3 children [\n  Shape { geometry Sphere { radius 0.5 } }\n  Shape { appearance NULL geometry IndexedFaceSet { solid FALSE coord Coordinate { point [ 0 0 0, 1 0 0, 0 1 0, 1 1 0 ] } coordIndex [ 0 1 2 -1 1 3 2 ] } }\n ] }\n";
        let nodes = parse_vrml(text).unwrap();
        assert_eq!(nodes.len(), 1);
        assert_eq!(nodes[0].kind, "Transform");
        assert_eq!(nodes[0].numbers("translation"), &[1.0, 2.0, 3.0]);
        let s = parse_vrml_summary(text).unwrap();
        assert_eq!(s.n_spheres, 1);
        assert_eq!(s.n_points, 4);
        assert_eq!(s.n_faces, 2);
        assert_eq!(s.n_colors, 0);
    }

    #[test]
    fn parser_rejects_broken_input() {
        assert_eq!(parse_vrml("Shape {}"), Err(VrmlError::Header));
        assert!(parse_vrml("#VRML V2.0 utf8\nShape { geometry Sphere { radius 1 }").is_err());
        assert!(parse_vrml("#VRML V2.0 utf8\nShape { coordIndex [ 1 2 ").is_err());
        assert!(parse_vrml("#VRML V2.0 utf8\n}").is_err());
    }
}
