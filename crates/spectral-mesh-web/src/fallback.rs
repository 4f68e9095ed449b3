//! Stand-ins for library pieces that other parts of the project provide: an OFF reader
//! and two procedural shapes. They are used only until the library's `io` and `shapes`
//! modules land, and are deliberately small.

use spectral_mesh::Mesh;

/// Reads an OFF file (polygons are fan-triangulated). Errors name the line.
pub fn read_off(bytes: &[u8]) -> Result<Mesh, String> {
    let text = std::str::from_utf8(bytes).map_err(|_| "the file is not UTF-8 text".to_string())?;
    let mut tokens = Vec::new();
    for (line_no, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("");
        for tok in line.split_whitespace() {
            tokens.push((line_no + 1, tok));
        }
    }
    let mut it = tokens.into_iter();
    let (_, head) = it.next().ok_or("the file is empty")?;
    let mut first_count = None;
    if head != "OFF" {
        if let Some(rest) = head.strip_prefix("OFF") {
            first_count = Some(rest.to_string());
        } else {
            return Err(format!("line 1: expected 'OFF', found '{head}'"));
        }
    }
    let mut next_num = |what: &str| -> Result<(usize, String), String> {
        match it.next() {
            Some((l, t)) => Ok((l, t.to_string())),
            None => Err(format!("unexpected end of file while reading {what}")),
        }
    };
    let parse_usize = |(l, t): (usize, String), what: &str| -> Result<usize, String> {
        t.parse::<usize>()
            .map_err(|_| format!("line {l}: expected {what}, found '{t}'"))
    };
    let nv = match first_count {
        Some(t) if !t.is_empty() => parse_usize((1, t), "vertex count")?,
        _ => parse_usize(next_num("the vertex count")?, "vertex count")?,
    };
    let nf = parse_usize(next_num("the face count")?, "face count")?;
    let _ne = next_num("the edge count")?;
    if nv > 50_000_000 || nf > 100_000_000 {
        return Err(format!("absurd counts: {nv} vertices, {nf} faces"));
    }
    let mut positions = Vec::with_capacity(nv);
    for _ in 0..nv {
        let mut p = [0.0; 3];
        for c in &mut p {
            let (l, t) = next_num("a vertex")?;
            *c = t
                .parse::<f64>()
                .map_err(|_| format!("line {l}: expected a coordinate, found '{t}'"))?;
        }
        positions.push(p);
    }
    let mut triangles = Vec::with_capacity(nf);
    for _ in 0..nf {
        let deg = parse_usize(next_num("a face")?, "a face size")?;
        if !(3..=1000).contains(&deg) {
            return Err(format!("a face has {deg} corners"));
        }
        let mut idx = Vec::with_capacity(deg);
        for _ in 0..deg {
            idx.push(parse_usize(next_num("a face")?, "a vertex index")?);
        }
        for j in 1..deg - 1 {
            triangles.push([idx[0], idx[j], idx[j + 1]]);
        }
    }
    Mesh::new(positions, triangles).map_err(|e| e.to_string())
}

/// An icosphere: the icosahedron subdivided `res` times, on the unit sphere.
pub fn icosphere(res: usize) -> Mesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut p: Vec<[f64; 3]> = vec![
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ];
    let mut f: Vec<[usize; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..res.min(7) {
        let mut mid = std::collections::HashMap::new();
        let mut nf = Vec::with_capacity(f.len() * 4);
        let mut midpoint = |a: usize, b: usize, p: &mut Vec<[f64; 3]>| -> usize {
            let key = (a.min(b), a.max(b));
            *mid.entry(key).or_insert_with(|| {
                let m = spectral_mesh::mesh::scale(spectral_mesh::mesh::add(p[a], p[b]), 0.5);
                p.push(m);
                p.len() - 1
            })
        };
        for &[a, b, c] in &f {
            let ab = midpoint(a, b, &mut p);
            let bc = midpoint(b, c, &mut p);
            let ca = midpoint(c, a, &mut p);
            nf.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = nf;
    }
    for q in &mut p {
        *q = spectral_mesh::mesh::normalize(*q);
    }
    // The construction is valid by design; fall back to the bare icosahedron otherwise.
    match Mesh::new(p, f) {
        Ok(m) => m,
        Err(_) => unreachable_mesh(),
    }
}

fn unreachable_mesh() -> Mesh {
    // A single triangle: only reached if the construction above were wrong.
    match Mesh::new(
        vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        vec![[0, 1, 2]],
    ) {
        Ok(m) => m,
        Err(_) => std::process::abort(),
    }
}

/// A torus of radii `r_big`, `r_small` with `nu x nv` quads split into triangles.
pub fn torus(nu: usize, nv: usize, r_big: f64, r_small: f64) -> Mesh {
    let (nu, nv) = (nu.clamp(3, 2000), nv.clamp(3, 2000));
    let mut p = Vec::with_capacity(nu * nv);
    for i in 0..nu {
        let u = i as f64 / nu as f64 * std::f64::consts::TAU;
        for j in 0..nv {
            let v = j as f64 / nv as f64 * std::f64::consts::TAU;
            p.push([
                (r_big + r_small * v.cos()) * u.cos(),
                (r_big + r_small * v.cos()) * u.sin(),
                r_small * v.sin(),
            ]);
        }
    }
    let id = |i: usize, j: usize| (i % nu) * nv + (j % nv);
    let mut f = Vec::with_capacity(2 * nu * nv);
    for i in 0..nu {
        for j in 0..nv {
            f.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            f.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    match Mesh::new(p, f) {
        Ok(m) => m,
        Err(_) => unreachable_mesh(),
    }
}

/// Parses `name[:key=value,...]` for the stand-in shapes `sphere` and `torus`.
pub fn build_shape(spec: &str) -> Result<Mesh, String> {
    let (name, args) = spec.split_once(':').unwrap_or((spec, ""));
    let mut kv = std::collections::HashMap::new();
    for part in args.split(',').filter(|s| !s.trim().is_empty()) {
        let (k, v) = part
            .split_once('=')
            .ok_or_else(|| format!("bad shape parameter '{part}': expected key=value"))?;
        let v: f64 = v
            .trim()
            .parse()
            .map_err(|_| format!("bad value in shape parameter '{part}'"))?;
        if !v.is_finite() {
            return Err(format!("bad value in shape parameter '{part}'"));
        }
        kv.insert(k.trim().to_string(), v);
    }
    let get = |k: &str, d: f64| kv.get(k).copied().unwrap_or(d);
    match name.trim() {
        "sphere" => {
            let res = get("res", 3.0);
            if !(0.0..=7.0).contains(&res) {
                return Err("sphere: res must be in 0..=7".into());
            }
            Ok(icosphere(res as usize))
        }
        "torus" => {
            let res = get("res", 48.0);
            if !(3.0..=2000.0).contains(&res) {
                return Err("torus: res must be in 3..=2000".into());
            }
            Ok(torus(res as usize, (res / 2.0).max(3.0) as usize, 1.0, 0.4))
        }
        other => Err(format!(
            "unknown shape '{other}': expected one of sphere, torus"
        )),
    }
}

/// Names of the stand-in shapes.
pub fn shape_names() -> Vec<(&'static str, &'static str)> {
    vec![
        ("sphere", "icosphere, sphere:res=0..7 subdivisions"),
        ("torus", "torus, torus:res=N segments"),
    ]
}
