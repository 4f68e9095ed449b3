//! The text form of a perturbation, as typed on the command line or stored in a study
//! file, and its application to a mesh.
//!
//! Grammar: `NAME` or `NAME:ARG,ARG,...`, where an argument is a number (positional) or
//! `key=value`. A centre is either three positional numbers `x,y,z` or `v=INDEX` (the
//! position of a vertex of the input mesh). Vectors inside a value use `/`
//! (`axis=1/1/0`). Angles are in degrees.
//!
//! | form | meaning |
//! |---|---|
//! | `noise:MAG[,seed=S]` | normal noise, sigma = MAG x mean edge length ([`super::noise`]) |
//! | `scale:ALPHA` | uniform scaling about the centroid ([`super::scale`]) |
//! | `localscale:x,y,z,R,ALPHA` or `localscale:v=I,R,ALPHA` | local scaling ([`super::local_scale`]) |
//! | `rotate:axis=x\|y\|z\|a/b/c,angle=DEG[,t=dx/dy/dz]` (or `rotate:DEG`, axis z) | rigid motion ([`super::rigid_motion`]) |
//! | `translate:dx,dy,dz` | translation |
//! | `resample:FACTOR[,seed=S]` | FACTOR x as many vertices, same surface ([`super::resample`]) |
//! | `refine:x,y,z,R,LEVELS` or `refine:v=I,R,LEVELS` | local refinement ([`super::refine_locally`]) |
//! | `hole:x,y,z,R` or `hole:v=I,R` | hole ([`super::hole`]) |
//! | `tiny:COUNT[,seed=S]` | tiny triangles ([`super::tiny_triangles`]) |
//! | `missing:COUNT[,seed=S]` | missing triangles ([`super::missing_triangles`]) |
//! | `bend:DEG[,axis=x\|y\|z]` | near-isometric bend ([`super::bend`]) |
//!
//! Seeds default to 0. [`PerturbationSpec`]'s `Display` writes the canonical form, which
//! parses back to the same spec.

use std::fmt;
use std::str::FromStr;

use super::{PerturbError, Perturbed};
use crate::mesh::Mesh;

/// Where a local perturbation is centred.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Center {
    /// A point in space.
    Point([f64; 3]),
    /// The position of this vertex of the input mesh.
    Vertex(usize),
}

impl Center {
    /// The point this centre denotes on `mesh`.
    pub fn resolve(&self, mesh: &Mesh) -> Result<[f64; 3], PerturbError> {
        match *self {
            Center::Point(p) => Ok(p),
            Center::Vertex(v) => {
                mesh.positions()
                    .get(v)
                    .copied()
                    .ok_or_else(|| PerturbError::InvalidParameter {
                        name: "centre vertex",
                        value: v.to_string(),
                        reason: format!("the mesh has {} vertices", mesh.n_vertices()),
                    })
            }
        }
    }
}

impl fmt::Display for Center {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Center::Point(p) => write!(f, "{},{},{}", p[0], p[1], p[2]),
            Center::Vertex(v) => write!(f, "v={v}"),
        }
    }
}

/// A parsed perturbation (see the module notes for the text form).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum PerturbationSpec {
    /// Normal noise with sigma = `magnitude` x mean edge length.
    Noise {
        /// Relative magnitude.
        magnitude: f64,
        /// Random seed.
        seed: u64,
    },
    /// Uniform scaling about the centroid.
    Scale {
        /// Factor.
        alpha: f64,
    },
    /// Local scaling with smooth falloff.
    LocalScale {
        /// Centre.
        center: Center,
        /// Radius of influence.
        radius: f64,
        /// Factor at the centre.
        alpha: f64,
    },
    /// Rotation about an axis through the origin, then translation.
    RigidMotion {
        /// Axis direction (any non-zero vector).
        axis: [f64; 3],
        /// Angle in degrees.
        angle_deg: f64,
        /// Translation.
        translation: [f64; 3],
    },
    /// Re-triangulation with `factor` times as many vertices.
    Resample {
        /// Vertex-count factor (>= 1).
        factor: f64,
        /// Random seed.
        seed: u64,
    },
    /// Local refinement in a ball.
    Refine {
        /// Centre.
        center: Center,
        /// Radius.
        radius: f64,
        /// Refinement rounds.
        levels: usize,
    },
    /// Hole cut by a ball.
    Hole {
        /// Centre.
        center: Center,
        /// Radius.
        radius: f64,
    },
    /// Tiny triangles.
    Tiny {
        /// Triangles split.
        count: usize,
        /// Random seed.
        seed: u64,
    },
    /// Missing triangles.
    Missing {
        /// Triangles deleted.
        count: usize,
        /// Random seed.
        seed: u64,
    },
    /// Near-isometric bend.
    Bend {
        /// Total bending angle in degrees.
        angle_deg: f64,
        /// Bent axis (0 = x, 1 = y, 2 = z), `None` = longest bounding-box side.
        axis: Option<usize>,
    },
}

const AXES: [&str; 3] = ["x", "y", "z"];

fn vec3(v: [f64; 3]) -> String {
    format!("{}/{}/{}", v[0], v[1], v[2])
}

impl fmt::Display for PerturbationSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PerturbationSpec::Noise { magnitude, seed } => {
                write!(f, "noise:{magnitude},seed={seed}")
            }
            PerturbationSpec::Scale { alpha } => write!(f, "scale:{alpha}"),
            PerturbationSpec::LocalScale {
                center,
                radius,
                alpha,
            } => write!(f, "localscale:{center},{radius},{alpha}"),
            PerturbationSpec::RigidMotion {
                axis,
                angle_deg,
                translation,
            } => write!(
                f,
                "rotate:axis={},angle={angle_deg},t={}",
                vec3(*axis),
                vec3(*translation)
            ),
            PerturbationSpec::Resample { factor, seed } => {
                write!(f, "resample:{factor},seed={seed}")
            }
            PerturbationSpec::Refine {
                center,
                radius,
                levels,
            } => write!(f, "refine:{center},{radius},{levels}"),
            PerturbationSpec::Hole { center, radius } => write!(f, "hole:{center},{radius}"),
            PerturbationSpec::Tiny { count, seed } => write!(f, "tiny:{count},seed={seed}"),
            PerturbationSpec::Missing { count, seed } => write!(f, "missing:{count},seed={seed}"),
            PerturbationSpec::Bend { angle_deg, axis } => match axis {
                Some(a) if *a < 3 => write!(f, "bend:{angle_deg},axis={}", AXES[*a]),
                _ => write!(f, "bend:{angle_deg}"),
            },
        }
    }
}

impl FromStr for PerturbationSpec {
    type Err = PerturbError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        parse_perturbation(s)
    }
}

fn perr(token: &str, reason: impl Into<String>) -> PerturbError {
    PerturbError::Parse {
        token: token.to_string(),
        reason: reason.into(),
    }
}

/// The arguments of one spec, consumed by the form that parses them.
struct Args<'a> {
    name: &'a str,
    positional: Vec<&'a str>,
    keyed: Vec<(&'a str, &'a str, &'a str, bool)>,
}

impl<'a> Args<'a> {
    fn new(name: &'a str, rest: Option<&'a str>) -> Result<Self, PerturbError> {
        let mut positional = Vec::new();
        let mut keyed = Vec::new();
        if let Some(rest) = rest {
            for tok in rest.split(',') {
                let tok = tok.trim();
                if tok.is_empty() {
                    return Err(perr(
                        rest,
                        "empty argument (two commas in a row, or a trailing comma)",
                    ));
                }
                match tok.split_once('=') {
                    Some((k, v)) => keyed.push((k.trim(), v.trim(), tok, false)),
                    None => positional.push(tok),
                }
            }
        }
        Ok(Self {
            name,
            positional,
            keyed,
        })
    }

    fn key(&mut self, k: &str) -> Option<(&'a str, &'a str)> {
        for e in self.keyed.iter_mut() {
            if e.0.eq_ignore_ascii_case(k) && !e.3 {
                e.3 = true;
                return Some((e.1, e.2));
            }
        }
        None
    }

    fn num(tok: &str) -> Result<f64, PerturbError> {
        tok.parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| perr(tok, "expected a finite number"))
    }

    fn int(tok: &str) -> Result<u64, PerturbError> {
        tok.parse::<u64>()
            .map_err(|_| perr(tok, "expected a non-negative integer"))
    }

    fn seed(&mut self) -> Result<u64, PerturbError> {
        match self.key("seed") {
            Some((v, tok)) => {
                Self::int(v).map_err(|_| perr(tok, "seed must be a non-negative integer"))
            }
            None => Ok(0),
        }
    }

    fn usize_of(tok: &str) -> Result<usize, PerturbError> {
        Self::int(tok).and_then(|x| usize::try_from(x).map_err(|_| perr(tok, "too large")))
    }

    /// A centre: `v=I` or the first three positional numbers.
    fn center(&mut self, pos: &mut usize) -> Result<Center, PerturbError> {
        if let Some((v, tok)) = self.key("v").or_else(|| self.key("vertex")) {
            let i = Self::usize_of(v)
                .map_err(|_| perr(tok, "vertex index must be a non-negative integer"))?;
            return Ok(Center::Vertex(i));
        }
        let mut c = [0.0; 3];
        for (k, ck) in c.iter_mut().enumerate() {
            let tok = self.positional.get(*pos + k).ok_or_else(|| {
                perr(
                    self.name,
                    "expected a centre: x,y,z or v=VERTEX before the other arguments",
                )
            })?;
            *ck = Self::num(tok)?;
        }
        *pos += 3;
        Ok(Center::Point(c))
    }

    /// Positional argument `*pos` or the keyed alternative `k`.
    fn next_or_key(
        &mut self,
        pos: &mut usize,
        k: &str,
        what: &str,
    ) -> Result<&'a str, PerturbError> {
        if let Some((v, _)) = self.key(k) {
            return Ok(v);
        }
        let tok = self
            .positional
            .get(*pos)
            .copied()
            .ok_or_else(|| perr(self.name, format!("missing {what}")))?;
        *pos += 1;
        Ok(tok)
    }

    /// Fails on any argument not consumed.
    fn finish(&self, pos: usize, expected: &str) -> Result<(), PerturbError> {
        if let Some(tok) = self.positional.get(pos) {
            return Err(perr(
                tok,
                format!("unexpected argument; expected {expected}"),
            ));
        }
        if let Some(e) = self.keyed.iter().find(|e| !e.3) {
            return Err(perr(
                e.2,
                format!("unknown or repeated option; expected {expected}"),
            ));
        }
        Ok(())
    }
}

fn axis_name(tok: &str, v: &str) -> Result<usize, PerturbError> {
    match v.to_ascii_lowercase().as_str() {
        "x" | "0" => Ok(0),
        "y" | "1" => Ok(1),
        "z" | "2" => Ok(2),
        _ => Err(perr(tok, "expected an axis x, y or z")),
    }
}

fn vector(tok: &str, v: &str) -> Result<[f64; 3], PerturbError> {
    let parts: Vec<&str> = v.split('/').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(perr(
            tok,
            "expected three numbers separated by '/', e.g. 1/0/0",
        ));
    }
    let mut out = [0.0; 3];
    for (o, p) in out.iter_mut().zip(&parts) {
        *o = Args::num(p).map_err(|_| perr(tok, format!("'{p}' is not a finite number")))?;
    }
    Ok(out)
}

/// Parses the text form of a perturbation (see the module notes). Errors name the
/// offending token.
pub fn parse_perturbation(s: &str) -> Result<PerturbationSpec, PerturbError> {
    let s = s.trim();
    let (name, rest) = match s.split_once(':') {
        Some((n, r)) => (n.trim(), Some(r)),
        None => (s, None),
    };
    let lname = name.to_ascii_lowercase().replace(['-', '_'], "");
    let mut a = Args::new(name, rest)?;
    let mut pos = 0;
    let spec = match lname.as_str() {
        "noise" => {
            let magnitude = Args::num(a.next_or_key(&mut pos, "magnitude", "noise magnitude")?)?;
            let seed = a.seed()?;
            a.finish(pos, "noise:MAGNITUDE[,seed=S]")?;
            PerturbationSpec::Noise { magnitude, seed }
        }
        "scale" => {
            let alpha = Args::num(a.next_or_key(&mut pos, "alpha", "scale factor")?)?;
            a.finish(pos, "scale:ALPHA")?;
            PerturbationSpec::Scale { alpha }
        }
        "localscale" => {
            let center = a.center(&mut pos)?;
            let radius = Args::num(a.next_or_key(&mut pos, "r", "radius")?)?;
            let alpha = Args::num(a.next_or_key(&mut pos, "alpha", "scale factor")?)?;
            a.finish(pos, "localscale:x,y,z,R,ALPHA or localscale:v=I,R,ALPHA")?;
            PerturbationSpec::LocalScale {
                center,
                radius,
                alpha,
            }
        }
        "rotate" | "rotation" | "rigid" => {
            let axis = match a.key("axis") {
                Some((v, tok)) => {
                    if v.contains('/') {
                        vector(tok, v)?
                    } else {
                        let mut e = [0.0; 3];
                        e[axis_name(tok, v)?] = 1.0;
                        e
                    }
                }
                None => [0.0, 0.0, 1.0],
            };
            let angle_deg = Args::num(a.next_or_key(&mut pos, "angle", "angle=DEGREES")?)?;
            let translation = match a.key("t").or_else(|| a.key("translation")) {
                Some((v, tok)) => vector(tok, v)?,
                None => [0.0; 3],
            };
            a.finish(pos, "rotate:axis=x|y|z|a/b/c,angle=DEG[,t=dx/dy/dz]")?;
            PerturbationSpec::RigidMotion {
                axis,
                angle_deg,
                translation,
            }
        }
        "translate" | "translation" => {
            let mut t = [0.0; 3];
            for (k, tk) in t.iter_mut().enumerate() {
                *tk =
                    Args::num(a.next_or_key(&mut pos, AXES[k], "three displacements dx,dy,dz")?)?;
            }
            a.finish(pos, "translate:dx,dy,dz")?;
            PerturbationSpec::RigidMotion {
                axis: [0.0, 0.0, 1.0],
                angle_deg: 0.0,
                translation: t,
            }
        }
        "resample" => {
            let factor = Args::num(a.next_or_key(&mut pos, "factor", "vertex-count factor")?)?;
            let seed = a.seed()?;
            a.finish(pos, "resample:FACTOR[,seed=S]")?;
            PerturbationSpec::Resample { factor, seed }
        }
        "refine" => {
            let center = a.center(&mut pos)?;
            let radius = Args::num(a.next_or_key(&mut pos, "r", "radius")?)?;
            let tok = a.next_or_key(&mut pos, "levels", "number of levels")?;
            let levels = Args::usize_of(tok)?;
            a.finish(pos, "refine:x,y,z,R,LEVELS or refine:v=I,R,LEVELS")?;
            PerturbationSpec::Refine {
                center,
                radius,
                levels,
            }
        }
        "hole" => {
            let center = a.center(&mut pos)?;
            let radius = Args::num(a.next_or_key(&mut pos, "r", "radius")?)?;
            a.finish(pos, "hole:x,y,z,R or hole:v=I,R")?;
            PerturbationSpec::Hole { center, radius }
        }
        "tiny" | "tinytriangles" => {
            let count = Args::usize_of(a.next_or_key(&mut pos, "count", "triangle count")?)?;
            let seed = a.seed()?;
            a.finish(pos, "tiny:COUNT[,seed=S]")?;
            PerturbationSpec::Tiny { count, seed }
        }
        "missing" | "missingtriangles" => {
            let count = Args::usize_of(a.next_or_key(&mut pos, "count", "triangle count")?)?;
            let seed = a.seed()?;
            a.finish(pos, "missing:COUNT[,seed=S]")?;
            PerturbationSpec::Missing { count, seed }
        }
        "bend" => {
            let angle_deg =
                Args::num(a.next_or_key(&mut pos, "angle", "bend angle in degrees")?)?;
            let axis = match a.key("axis") {
                Some((v, tok)) => Some(axis_name(tok, v)?),
                None => None,
            };
            a.finish(pos, "bend:DEG[,axis=x|y|z]")?;
            PerturbationSpec::Bend { angle_deg, axis }
        }
        _ => {
            return Err(perr(
                name,
                "unknown perturbation; expected noise, scale, localscale, rotate, translate, resample, refine, hole, tiny, missing or bend",
            ));
        }
    };
    Ok(spec)
}

/// Applies a parsed perturbation to `mesh`.
pub fn apply(mesh: &Mesh, spec: &PerturbationSpec) -> Result<Perturbed, PerturbError> {
    match spec {
        PerturbationSpec::Noise { magnitude, seed } => super::noise(mesh, *magnitude, *seed),
        PerturbationSpec::Scale { alpha } => super::scale(mesh, *alpha),
        PerturbationSpec::LocalScale {
            center,
            radius,
            alpha,
        } => super::local_scale(mesh, center.resolve(mesh)?, *radius, *alpha),
        PerturbationSpec::RigidMotion {
            axis,
            angle_deg,
            translation,
        } => super::rigid_motion(mesh, *axis, angle_deg.to_radians(), *translation),
        PerturbationSpec::Resample { factor, seed } => {
            let f = super::finite("resample factor", *factor)?;
            if f < 1.0 {
                return Err(PerturbError::InvalidParameter {
                    name: "resample factor",
                    value: f.to_string(),
                    reason: "must be >= 1 (resampling only refines)".into(),
                });
            }
            let target = (f * mesh.n_vertices() as f64).round();
            if target > 1e9 {
                return Err(PerturbError::InvalidParameter {
                    name: "resample factor",
                    value: f.to_string(),
                    reason: "would ask for more than 10^9 vertices".into(),
                });
            }
            super::resample(mesh, target as usize, *seed)
        }
        PerturbationSpec::Refine {
            center,
            radius,
            levels,
        } => super::refine_locally(mesh, center.resolve(mesh)?, *radius, *levels),
        PerturbationSpec::Hole { center, radius } => {
            super::hole(mesh, center.resolve(mesh)?, *radius)
        }
        PerturbationSpec::Tiny { count, seed } => super::tiny_triangles(mesh, *count, *seed),
        PerturbationSpec::Missing { count, seed } => super::missing_triangles(mesh, *count, *seed),
        PerturbationSpec::Bend { angle_deg, axis } => {
            super::bend(mesh, *axis, angle_deg.to_radians())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_documented_forms() {
        assert_eq!(
            parse_perturbation("noise:0.1").unwrap(),
            PerturbationSpec::Noise {
                magnitude: 0.1,
                seed: 0
            }
        );
        assert_eq!(
            parse_perturbation(" noise:0.1, seed=3 ").unwrap(),
            PerturbationSpec::Noise {
                magnitude: 0.1,
                seed: 3
            }
        );
        assert_eq!(
            parse_perturbation("scale:2").unwrap(),
            PerturbationSpec::Scale { alpha: 2.0 }
        );
        assert_eq!(
            parse_perturbation("rotate:axis=z,angle=30").unwrap(),
            PerturbationSpec::RigidMotion {
                axis: [0.0, 0.0, 1.0],
                angle_deg: 30.0,
                translation: [0.0; 3]
            }
        );
        assert_eq!(
            parse_perturbation("rotate:axis=1/1/0,angle=45,t=1/2/3").unwrap(),
            PerturbationSpec::RigidMotion {
                axis: [1.0, 1.0, 0.0],
                angle_deg: 45.0,
                translation: [1.0, 2.0, 3.0]
            }
        );
        assert_eq!(
            parse_perturbation("resample:2").unwrap(),
            PerturbationSpec::Resample {
                factor: 2.0,
                seed: 0
            }
        );
        assert_eq!(
            parse_perturbation("refine:0.5,0,-1,0.25,2").unwrap(),
            PerturbationSpec::Refine {
                center: Center::Point([0.5, 0.0, -1.0]),
                radius: 0.25,
                levels: 2
            }
        );
        assert_eq!(
            parse_perturbation("hole:v=12,0.3").unwrap(),
            PerturbationSpec::Hole {
                center: Center::Vertex(12),
                radius: 0.3
            }
        );
        assert_eq!(
            parse_perturbation("tiny:100").unwrap(),
            PerturbationSpec::Tiny {
                count: 100,
                seed: 0
            }
        );
        assert_eq!(
            parse_perturbation("missing:20,seed=9").unwrap(),
            PerturbationSpec::Missing { count: 20, seed: 9 }
        );
        assert_eq!(
            parse_perturbation("bend:90").unwrap(),
            PerturbationSpec::Bend {
                angle_deg: 90.0,
                axis: None
            }
        );
        assert_eq!(
            parse_perturbation("bend:90,axis=y").unwrap(),
            PerturbationSpec::Bend {
                angle_deg: 90.0,
                axis: Some(1)
            }
        );
    }

    #[test]
    fn display_round_trips() {
        for s in [
            "noise:0.1,seed=3",
            "scale:0.5",
            "localscale:1,2,3,0.5,1.5",
            "localscale:v=4,0.5,1.5",
            "rotate:axis=0/1/0,angle=-30,t=0.1/0/2",
            "translate:1,2,3",
            "resample:1.5,seed=2",
            "refine:v=0,0.2,3",
            "hole:0,0,1,0.3",
            "tiny:5,seed=1",
            "missing:7",
            "bend:45,axis=x",
            "bend:-45",
        ] {
            let a = parse_perturbation(s).unwrap();
            let b = parse_perturbation(&a.to_string()).unwrap();
            assert_eq!(a, b, "{s} -> {a}");
        }
    }

    #[test]
    fn errors_name_the_bad_token() {
        let cases = [
            ("nosie:0.1", "nosie"),
            ("noise:abc", "abc"),
            ("noise:0.1,seed=-1", "seed=-1"),
            ("noise:0.1,sed=3", "sed=3"),
            ("noise:0.1,7", "7"),
            ("rotate:axis=w,angle=3", "axis=w"),
            ("rotate:axis=1/0,angle=3", "axis=1/0"),
            ("tiny:1.5", "1.5"),
            ("refine:1,2,3,0.5,x", "x"),
            ("scale:inf", "inf"),
        ];
        for (s, tok) in cases {
            match parse_perturbation(s) {
                Err(PerturbError::Parse { token, .. }) => assert_eq!(token, tok, "{s}"),
                other => panic!("{s}: expected a parse error, got {other:?}"),
            }
        }
        // Missing arguments name the perturbation.
        match parse_perturbation("hole:1,2") {
            Err(PerturbError::Parse { token, .. }) => assert_eq!(token, "hole"),
            other => panic!("{other:?}"),
        }
        assert!(parse_perturbation("noise").is_err());
        assert!(parse_perturbation("noise:0.1,,seed=2").is_err());
    }
}
