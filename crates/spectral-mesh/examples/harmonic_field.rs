//! Writes a harmonic or bi-harmonic field for the conformance script
//! `conformance/harmonic_libigl.py`.
//!
//! ```text
//! cargo run -p spectral-mesh --example harmonic_field -- MESH.off ORDER LAPLACIAN OUT.txt [V=X ... | extremes=K]
//! ```
//!
//! Writes `OUT.txt` (one value per line, shortest round-trip decimal) and prints the
//! constraints used, one `VERTEX VALUE` per line, on standard output (the constraints-file
//! format). Without constraints, `extremes=2` (the paper's default) is used.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::io::Write;
use std::process::ExitCode;

use spectral_mesh::fields::harmonic::{
    ConstraintSpec, HarmonicParams, harmonic_map, parse_constraint_arg,
};
use spectral_mesh::{Laplacian, Mesh};

/// STOP-GAP plain-OFF reader (vertices, then polygons fan-triangulated), used until the
/// crate's `io` module has its reader. Handles `#` comments and an optional "OFF" header
/// carrying the counts on the same line.
fn read_off(path: &str) -> Result<Mesh, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{path}: {e}"))?;
    let mut tokens = text
        .lines()
        .map(|l| l.split('#').next().unwrap_or(""))
        .flat_map(|l| l.split_whitespace())
        .peekable();
    if tokens.peek().is_some_and(|t| t.ends_with("OFF")) {
        tokens.next();
    }
    let mut num = |what: &str| -> Result<f64, String> {
        let t = tokens
            .next()
            .ok_or(format!("{path}: file ends before {what}"))?;
        t.parse::<f64>()
            .map_err(|_| format!("{path}: bad {what} '{t}'"))
    };
    let nv = num("vertex count")? as usize;
    let nf = num("face count")? as usize;
    let _ne = num("edge count")?;
    let mut p = Vec::with_capacity(nv);
    for _ in 0..nv {
        p.push([num("x")?, num("y")?, num("z")?]);
    }
    let mut t = Vec::with_capacity(nf);
    for _ in 0..nf {
        let k = num("polygon size")? as usize;
        let mut poly = Vec::with_capacity(k);
        for _ in 0..k {
            poly.push(num("vertex index")? as usize);
        }
        for i in 1..k.saturating_sub(1) {
            t.push([poly[0], poly[i], poly[i + 1]]);
        }
    }
    Mesh::new(p, t).map_err(|e| format!("{path}: {e}"))
}

fn run(args: &[String]) -> Result<(), String> {
    if args.len() < 4 {
        return Err(
            "usage: harmonic_field MESH.off ORDER LAPLACIAN OUT.txt [V=X ... | extremes=K]".into(),
        );
    }
    let mesh = read_off(&args[0])?;
    let order: u32 = args[1]
        .parse()
        .map_err(|_| format!("bad order '{}'", args[1]))?;
    let laplacian: Laplacian = args[2].parse()?;
    let spec = match &args[4..] {
        [] => ConstraintSpec::Extremes(2),
        [one] if one.starts_with("extremes=") => {
            let k = one["extremes=".len()..]
                .parse()
                .map_err(|_| format!("bad '{one}'"))?;
            ConstraintSpec::Extremes(k)
        }
        rest => ConstraintSpec::Explicit(
            rest.iter()
                .map(|a| parse_constraint_arg(a))
                .collect::<Result<_, _>>()
                .map_err(|e| e.to_string())?,
        ),
    };
    let cons = spec.resolve(&mesh).map_err(|e| e.to_string())?;
    let f = harmonic_map(&mesh, &cons, &HarmonicParams { order, laplacian })
        .map_err(|e| e.to_string())?;
    let mut out = String::with_capacity(f.len() * 24);
    for x in &f {
        out.push_str(&format!("{x:e}\n"));
    }
    std::fs::write(&args[3], out).map_err(|e| format!("{}: {e}", args[3]))?;
    let mut so = std::io::stdout().lock();
    for c in &cons {
        writeln!(so, "{} {:e}", c.vertex, c.value).map_err(|e| e.to_string())?;
    }
    Ok(())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
