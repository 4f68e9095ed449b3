//! Writes heat kernel columns, bi-harmonic distances and HKS of an OFF mesh as text files,
//! for the conformance script `conformance/heat_distances.py`.
//!
//! Usage: `spectral_fields MESH.off OUTDIR K T ANCHOR...`
//! Files: `eigenvalues.txt` (k), `heat_<i>.txt` (wFEM `K_t e_i`, n), `biharmonic_<i>.txt`
//! (n), `hks_times.txt` (auto times), `hks.txt` (n rows, one column per time, unscaled),
//! `commute_<i>.txt` (n). The basis comes from `compute_eigenbasis` (the engine every
//! command uses: dense for small meshes, block shift-invert above).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::error::Error;
use std::fs;
use std::io::Write;
use std::path::Path;

use spectral_mesh::spectral::distances::distances_from;
use spectral_mesh::spectral::filters::Filter;
use spectral_mesh::spectral::heat::{Kernel, basis_function};
use spectral_mesh::spectral::signatures::{hks, hks_auto_times};
use spectral_mesh::{Laplacian, Mesh, Operators};

/// A minimal OFF / COFF reader (comments, colour columns after x y z ignored; polygons fanned).
fn read_off(path: &Path) -> Result<Mesh, Box<dyn Error>> {
    let text = fs::read_to_string(path)?;
    let mut tokens = text
        .lines()
        .map(|l| l.split('#').next().unwrap_or(""))
        .filter(|l| !l.trim().is_empty());
    let header = tokens.next().ok_or("empty file")?;
    let mut first: Vec<&str> = header.split_whitespace().collect();
    if first[0].ends_with("OFF") {
        first.remove(0);
    }
    let counts: Vec<usize> = if first.is_empty() {
        tokens
            .next()
            .ok_or("no counts")?
            .split_whitespace()
            .map(|s| s.parse())
            .collect::<Result<_, _>>()?
    } else {
        first.iter().map(|s| s.parse()).collect::<Result<_, _>>()?
    };
    let (nv, nf) = (counts[0], counts[1]);
    let mut pos = Vec::with_capacity(nv);
    for _ in 0..nv {
        let v: Vec<f64> = tokens
            .next()
            .ok_or("missing vertex")?
            .split_whitespace()
            .take(3)
            .map(|s| s.parse())
            .collect::<Result<_, _>>()?;
        pos.push([v[0], v[1], v[2]]);
    }
    let mut tris = Vec::new();
    for _ in 0..nf {
        let f: Vec<usize> = tokens
            .next()
            .ok_or("missing face")?
            .split_whitespace()
            .map(|s| s.parse())
            .collect::<Result<_, _>>()?;
        let m = f[0];
        for j in 1..m - 1 {
            tris.push([f[1], f[1 + j], f[2 + j]]);
        }
    }
    Ok(Mesh::new(pos, tris)?)
}

fn write(path: &Path, v: &[f64]) -> Result<(), Box<dyn Error>> {
    let mut f = fs::File::create(path)?;
    for x in v {
        writeln!(f, "{x:.17e}")?;
    }
    Ok(())
}

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 6 {
        return Err("usage: spectral_fields MESH.off OUTDIR K T ANCHOR...".into());
    }
    let mesh = read_off(Path::new(&args[1]))?;
    let out = Path::new(&args[2]);
    fs::create_dir_all(out)?;
    let k: usize = args[3].parse()?;
    let t: f64 = args[4].parse()?;
    let anchors: Vec<usize> = args[5..]
        .iter()
        .map(|s| s.parse())
        .collect::<Result<_, _>>()?;
    let ops = Operators::new(&mesh, Laplacian::Fem);
    let params = spectral_mesh::spectral::eigenbasis::EigenParams {
        k,
        ..Default::default()
    };
    let basis =
        spectral_mesh::spectral::eigenbasis::compute_eigenbasis(&ops, &params, &mut |_| {})?;
    write(&out.join("eigenvalues.txt"), &basis.values)?;
    for &a in &anchors {
        write(
            &out.join(format!("heat_{a}.txt")),
            &basis_function(&basis, a, t, Kernel::Wfem)?,
        )?;
        write(
            &out.join(format!("biharmonic_{a}.txt")),
            &distances_from(&basis, a, &Filter::Biharmonic)?,
        )?;
        write(
            &out.join(format!("commute_{a}.txt")),
            &distances_from(&basis, a, &Filter::CommuteTime)?,
        )?;
    }
    let times = hks_auto_times(&basis, 8)?;
    write(&out.join("hks_times.txt"), &times)?;
    let h = hks(&basis, &times, false);
    let mut f = fs::File::create(out.join("hks.txt"))?;
    for p in 0..basis.n {
        let row: Vec<String> = h.iter().map(|c| format!("{:.17e}", c[p])).collect();
        writeln!(f, "{}", row.join(" "))?;
    }
    println!("n = {}, k = {k}, wrote {}", basis.n, out.display());
    Ok(())
}
