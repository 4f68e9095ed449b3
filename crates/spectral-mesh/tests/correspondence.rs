//! Shape correspondence: the exact functional map, point maps, ZoomOut and the geodesic
//! evaluation on pairs with a known correspondence made here: a shape and a copy with
//! shuffled vertices (asymmetric, and mirror-symmetric with the orientation term), the
//! same surface at two resolutions, a shared mesh and its midpoint subdivision, and a
//! near-isometric bend.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use spectral_mesh::correspondence::{
    DescriptorParams, FmapProblem, FmapWeights, FunctionalMap, MatchParams, MatchShape,
    ZoomoutDirection, cumulative_curve, default_thresholds, descriptors, fmap_to_p2p,
    fmap_to_p2p_12, geodesic_errors, match_shapes, p2p_to_fmap, shuffled_copy, transfer,
    transfer_spectral, zoomout,
};
use spectral_mesh::geodesic::{GeodesicParams, GeodesicSolver};
use spectral_mesh::mesh::Mesh;
use spectral_mesh::perturb::rng::Rng;
use spectral_mesh::spectral::eigenbasis::{EigenParams, compute_eigenbasis};
use spectral_mesh::{Eigenbasis, Laplacian, Operators};

fn basis(mesh: &Mesh, k: usize) -> Eigenbasis {
    let ops = Operators::new(mesh, Laplacian::Fem);
    compute_eigenbasis(
        &ops,
        &EigenParams {
            k,
            ..EigenParams::default()
        },
        &mut |_| {},
    )
    .unwrap()
}

/// An icosphere deformed without any symmetry.
fn blob(res: u32) -> Mesh {
    let s = spectral_mesh::shapes::build_str(&format!("sphere:res={res}")).unwrap();
    s.map_positions(|[x, y, z]| {
        [
            1.6 * x + 0.35 * x * x + 0.2 * y,
            0.9 * y + 0.25 * z * z,
            0.7 * z + 0.3 * x * y + 0.15 * z * z * z,
        ]
    })
    .unwrap()
}

/// An icosphere deformed with the one mirror symmetry x -> -x.
fn mirror_blob(res: u32) -> Mesh {
    let s = spectral_mesh::shapes::build_str(&format!("sphere:res={res}")).unwrap();
    s.map_positions(|[x, y, z]| {
        [
            1.3 * x + 0.3 * x * x * x,
            1.8 * y + 0.4 * y * y,
            0.8 * z + 0.35 * y * z + 0.2 * x * x,
        ]
    })
    .unwrap()
}

/// The mesh with its vertices renumbered and the true map from the copy to it.
fn shuffled(mesh: &Mesh, seed: u64) -> (Mesh, Vec<usize>) {
    shuffled_copy(mesh, seed).unwrap()
}

/// For each vertex of `b`, the nearest vertex of `a` in space.
fn nearest_in_space(a: &Mesh, b: &Mesh) -> Vec<usize> {
    b.positions()
        .iter()
        .map(|p| {
            let mut best = (f64::INFINITY, 0);
            for (i, q) in a.positions().iter().enumerate() {
                let d = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2);
                if d < best.0 {
                    best = (d, i);
                }
            }
            best.1
        })
        .collect()
}

/// 1-to-4 midpoint subdivision (old vertices keep their indices).
fn subdivide(mesh: &Mesh) -> Mesh {
    let mut pos = mesh.positions().to_vec();
    let mut mid = std::collections::HashMap::new();
    let mut tris = Vec::new();
    let mut midpoint = |a: usize, b: usize, pos: &mut Vec<[f64; 3]>| -> usize {
        *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
            let (p, q) = (pos[a], pos[b]);
            pos.push([
                0.5 * (p[0] + q[0]),
                0.5 * (p[1] + q[1]),
                0.5 * (p[2] + q[2]),
            ]);
            pos.len() - 1
        })
    };
    for &[a, b, c] in mesh.triangles() {
        let ab = midpoint(a, b, &mut pos);
        let bc = midpoint(b, c, &mut pos);
        let ca = midpoint(c, a, &mut pos);
        tris.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
    }
    Mesh::new(pos, tris).unwrap()
}

/// Runs the pipeline (shape 1 = `m1`, shape 2 = `m2`) and returns the mean geodesic error
/// of `p2p_21` against `gt_21`, in units of `sqrt(area_1)`.
fn run_pair(m1: &Mesh, m2: &Mesh, gt_21: &[usize], params: &MatchParams) -> f64 {
    let k = params.basis_size();
    let (b1, b2) = (basis(m1, k), basis(m2, k));
    let res = match_shapes(m1, (&b1).into(), m2, (&b2).into(), &[], params).unwrap();
    assert_eq!(res.p2p_21.len(), m2.n_vertices());
    assert_eq!((res.refined.k1, res.refined.k2), (k, k));
    let solver = GeodesicSolver::new(m1, Laplacian::Fem, &GeodesicParams::default()).unwrap();
    let e = geodesic_errors(&solver, &res.p2p_21, gt_21, m1.area(), Some(400)).unwrap();
    let curve = cumulative_curve(&e.errors, &default_thresholds());
    assert!(curve.windows(2).all(|w| w[0] <= w[1]));
    assert!((curve[curve.len() - 1] - 1.0).abs() < 1e-12 || e.mean > 0.01);
    e.mean
}

/// [`run_pair`], printed under `label` and asserted below `bound`; returns the error.
fn assert_pair(
    label: &str,
    m1: &Mesh,
    m2: &Mesh,
    gt_21: &[usize],
    params: &MatchParams,
    bound: f64,
) -> f64 {
    let err = run_pair(m1, m2, gt_21, params);
    println!("{label}: mean geodesic error {err:.3e} sqrt(area)");
    assert!(err < bound, "{label}: mean error {err}");
    err
}

fn small_params() -> MatchParams {
    MatchParams {
        k: 20,
        zoomout_k: 60,
        ..MatchParams::default()
    }
}

#[test]
fn shuffled_asymmetric_pair_is_recovered() {
    let m1 = blob(3);
    let (m2, gt) = shuffled(&m1, 7);
    assert_pair("shuffled blob", &m1, &m2, &gt, &small_params(), 0.01);
}

#[test]
fn shuffled_mirror_symmetric_pair_keeps_left_and_right() {
    let m1 = mirror_blob(3);
    let (m2, gt) = shuffled(&m1, 11);
    let err = assert_pair(
        "shuffled mirror blob, orientation-preserving",
        &m1,
        &m2,
        &gt,
        &small_params(),
        0.01,
    );
    // The orientation-reversing term picks the mirror image: a large error.
    let mut rev = small_params();
    rev.weights.orientation = 1.0;
    rev.weights.orientation_reversing = true;
    let err_rev = run_pair(&m1, &m2, &gt, &rev);
    println!("shuffled mirror blob, orientation-reversing: {err_rev:.2e}");
    assert!(
        err_rev > 10.0 * err.max(1e-3),
        "reversing {err_rev}, preserving {err}"
    );
}

/// The share of `map` equal to `truth`.
fn exact_share(map: &[usize], truth: &[usize]) -> f64 {
    assert_eq!(map.len(), truth.len());
    map.iter().zip(truth).filter(|(a, b)| a == b).count() as f64 / map.len() as f64
}

#[test]
fn zoomout_in_both_directions_on_a_shuffled_pair() {
    let m1 = blob(3);
    let (m2, gt_21) = shuffled(&m1, 7);
    let mut gt_12 = vec![0; gt_21.len()];
    for (v, &u) in gt_21.iter().enumerate() {
        gt_12[u] = v;
    }
    let mut params = small_params();
    params.zoomout_direction = ZoomoutDirection::Both;
    let k = params.basis_size();
    let (b1, b2) = (basis(&m1, k), basis(&m2, k));
    let (v1, v2) = ((&b1).into(), (&b2).into());
    let both = match_shapes(&m1, v1, &m2, v2, &[], &params).unwrap();
    let rev = both.reverse.as_ref().expect("the reverse direction");
    assert_eq!((rev.fmap.k1, rev.fmap.k2), (k, k));
    assert_eq!(rev.p2p.len(), m1.n_vertices());
    // Each direction on its own: near-exact, and small geodesic errors (the reverse map
    // is measured on shape 2, the shape it maps into).
    let (s21, s12) = (
        exact_share(&both.p2p_21, &gt_21),
        exact_share(&rev.p2p, &gt_12),
    );
    println!("exact: forward {s21:.4}, reverse {s12:.4}");
    assert!(s21 > 0.99 && s12 > 0.99, "forward {s21}, reverse {s12}");
    let solver2 = GeodesicSolver::new(&m2, Laplacian::Fem, &GeodesicParams::default()).unwrap();
    let e12 = geodesic_errors(&solver2, &rev.p2p, &gt_12, m2.area(), Some(400)).unwrap();
    assert!(e12.mean < 0.01, "reverse mean error {}", e12.mean);
    // The two directions agree: the maps are inverse to each other and the functional
    // maps transposes (both orthogonal on an isometry).
    let round_trip = (0..m1.n_vertices())
        .filter(|&u| both.p2p_21[rev.p2p[u]] == u)
        .count() as f64
        / m1.n_vertices() as f64;
    assert!(round_trip > 0.99, "round trip {round_trip}");
    let back = both.refined.transpose();
    let diff: f64 = back
        .c
        .iter()
        .zip(&rev.fmap.c)
        .map(|(a, b)| (a - b) * (a - b))
        .sum();
    let norm: f64 = back.c.iter().map(|a| a * a).sum();
    assert!(
        diff.sqrt() < 0.05 * norm.sqrt(),
        "|C12 - C21^T| = {}",
        diff.sqrt()
    );
    // The forward direction alone is what `Both` gives forward, with no reverse map.
    params.zoomout_direction = ZoomoutDirection::Forward;
    let fwd = match_shapes(&m1, v1, &m2, v2, &[], &params).unwrap();
    assert!(fwd.reverse.is_none());
    assert_eq!(fwd.p2p_21, both.p2p_21);
    assert_eq!(fwd.refined, both.refined);
    // The reverse alone: the same reverse map; the forward one from the first map only.
    params.zoomout_direction = ZoomoutDirection::Reverse;
    let only = match_shapes(&m1, v1, &m2, v2, &[], &params).unwrap();
    assert_eq!(only.reverse.as_ref(), Some(rev));
    assert_eq!(only.refined, only.initial);
    assert_eq!(
        only.p2p_21,
        fmap_to_p2p(&only.initial, v1, v2, false).unwrap()
    );
    // The library's function: the reverse refinement is the forward one of the shapes
    // swapped, from the transpose.
    let z = zoomout(&both.initial, v1, v2, k, 1, ZoomoutDirection::Reverse).unwrap();
    assert!(z.forward.is_none());
    let swapped = zoomout(
        &both.initial.transpose(),
        v2,
        v1,
        k,
        1,
        ZoomoutDirection::Forward,
    )
    .unwrap();
    assert_eq!(z.reverse, swapped.forward);
    // Sizes the bases do not hold are refused, naming the shape.
    let e = zoomout(&both.initial, v1, v2, k + 1, 1, ZoomoutDirection::Reverse).unwrap_err();
    assert!(e.to_string().contains("shape 2's basis"), "{e}");
}

#[test]
fn zoomout_direction_names() {
    for d in ZoomoutDirection::ALL {
        assert_eq!(d.name().parse::<ZoomoutDirection>(), Ok(d));
        assert_eq!(serde_json::to_value(d).unwrap(), d.name());
    }
    assert_eq!(
        " Both ".parse::<ZoomoutDirection>(),
        Ok(ZoomoutDirection::Both)
    );
    let e = "sideways".parse::<ZoomoutDirection>().unwrap_err();
    assert!(e.contains("forward, reverse or both"), "{e}");
    let j = spectral_mesh::defaults::to_json();
    assert_eq!(
        j["correspondence"]["zoomout_direction"],
        MatchParams::default().zoomout_direction.name()
    );
    // Parameters written before the direction existed read as the default.
    let p: MatchParams = serde_json::from_str(r#"{"k": 12}"#).unwrap();
    assert_eq!(p.zoomout_direction, ZoomoutDirection::default());
}

#[test]
fn same_surface_at_two_resolutions() {
    let (m1, m2) = (blob(3), blob(4));
    let gt = nearest_in_space(&m1, &m2);
    assert_pair("blob res 3 <- res 4", &m1, &m2, &gt, &small_params(), 0.03);
}

#[test]
fn shared_mesh_and_its_subdivision() {
    let Some(path) = spectral_mesh_testkit::shared_mesh("cow.off") else {
        return;
    };
    let m1 = spectral_mesh::io::read_mesh(&path).unwrap().mesh;
    let m2 = subdivide(&m1);
    let gt = nearest_in_space(&m1, &m2);
    assert_pair(
        "cow <- subdivided cow",
        &m1,
        &m2,
        &gt,
        &small_params(),
        0.03,
    );
    // Shuffled cow with the default parameters (k = 30, ZoomOut to 100).
    let (m3, gt3) = shuffled(&m1, 3);
    assert_pair(
        "cow <- shuffled cow",
        &m1,
        &m3,
        &gt3,
        &MatchParams::default(),
        0.01,
    );
}

#[test]
fn near_isometric_bend() {
    // An elongated blob bent around the z axis (radius 8): lengths along the bend are
    // kept on the midsurface y = 0, within about 12% elsewhere.
    let long = blob(4).map_positions(|[x, y, z]| [1.5 * x, y, z]).unwrap();
    let r = 8.0;
    let bent = long
        .map_positions(|[x, y, z]| {
            let th = x / r;
            [(r + y) * th.sin(), (r + y) * th.cos() - r, z]
        })
        .unwrap();
    let (m2, gt) = shuffled(&bent, 5);
    assert_pair("bent blob", &long, &m2, &gt, &small_params(), 0.05);
}

#[test]
fn exact_solution_has_the_lowest_energy() {
    let m1 = blob(3);
    let (m2, _) = shuffled(&blob(3), 2);
    let m2 = m2
        .map_positions(|[x, y, z]| [x * 1.05, y, z * 0.97])
        .unwrap();
    let k = 12;
    let (b1, b2) = (basis(&m1, k), basis(&m2, k));
    let dp = DescriptorParams::default();
    let d1 = descriptors((&b1).into(), &dp, &[0, 40]).unwrap();
    let d2 = descriptors((&b2).into(), &dp, &[0, 40]).unwrap();
    assert_eq!(d1.p, (100 + 200usize).div_ceil(5));
    for weights in [
        FmapWeights::default(),
        FmapWeights {
            orientation: 0.0,
            fix_constant: false,
            ..FmapWeights::default()
        },
        FmapWeights {
            commutativity: 0.0,
            orientation: 1.0,
            orientation_reversing: true,
            ..FmapWeights::default()
        },
    ] {
        let problem = FmapProblem::new(
            MatchShape {
                mesh: &m1,
                basis: (&b1).into(),
                descriptors: &d1,
            },
            MatchShape {
                mesh: &m2,
                basis: (&b2).into(),
                descriptors: &d2,
            },
            &weights,
        )
        .unwrap();
        let c = problem.solve().unwrap();
        let e0 = problem.energy(&c);
        // The gradient vanishes on the free entries.
        let g = problem.gradient(&c);
        let gmax = g.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(gmax < 1e-9 * (1.0 + e0), "gradient {gmax}");
        if weights.fix_constant {
            assert!((c.get(0, 0) - (m2.area() / m1.area()).sqrt()).abs() < 1e-12);
            assert!((1..k).all(|i| c.get(i, 0) == 0.0));
        }
        // Any perturbation of the free entries raises the energy.
        let mut rng = Rng::new(99);
        let first = if weights.fix_constant { k } else { 0 };
        for scale in [1e-6, 1e-3, 1e-1] {
            for _ in 0..5 {
                let mut p = c.clone();
                for v in &mut p.c[first..] {
                    *v += scale * (rng.uniform() - 0.5);
                }
                let e = problem.energy(&p);
                assert!(e >= e0 - 1e-12 * e0.abs(), "{e} < {e0}");
            }
        }
        // The energy is quadratic: E(c + t d) - E(c) = t^2 / 2 d^T H d at the minimum.
        let terms = problem.terms(&c);
        assert!((terms.total() - e0).abs() <= 1e-15 * e0.abs().max(1.0));
    }
}

#[test]
fn point_maps_are_exact_on_the_identity() {
    let m = blob(3);
    let k = 30;
    let b = basis(&m, k);
    let n = m.n_vertices();
    let id = FunctionalMap::identity(k, k);
    let view = (&b).into();
    let ident: Vec<usize> = (0..n).collect();
    assert_eq!(fmap_to_p2p(&id, view, view, false).unwrap(), ident);
    assert_eq!(fmap_to_p2p(&id, view, view, true).unwrap(), ident);
    assert_eq!(fmap_to_p2p_12(&id, view, view).unwrap(), ident);
    // The functional map of the identity is the identity (B-orthonormal basis).
    let c = p2p_to_fmap(&ident, view, view, k, k).unwrap();
    for j in 0..k {
        for i in 0..k {
            let want = if i == j { 1.0 } else { 0.0 };
            assert!(
                (c.get(i, j) - want).abs() < 1e-9,
                "C[{i},{j}] = {}",
                c.get(i, j)
            );
        }
    }
    // A shuffle: the point map's functional map sends each function to itself.
    let (m2, perm) = shuffled(&m, 4);
    let b2 = basis(&m2, k);
    let c = p2p_to_fmap(&perm, view, (&b2).into(), k, k).unwrap();
    let p2p = fmap_to_p2p(&c, view, (&b2).into(), false).unwrap();
    assert_eq!(p2p, perm);
    // Transfer: pointwise equals a gather; spectral transfer of an eigenvector is exact.
    let f: Vec<f64> = m.positions().iter().map(|p| p[0]).collect();
    let g = transfer(&perm, &f, n, 1).unwrap();
    assert!((0..n).all(|i| g[i] == f[perm[i]]));
    let x3 = b.vector(3).to_vec();
    let t = transfer_spectral(&c, view, (&b2).into(), &x3, 1).unwrap();
    let err = (0..n)
        .map(|i| (t[i] - x3[perm[i]]).abs())
        .fold(0.0, f64::max);
    assert!(err < 1e-8, "spectral transfer error {err}");
}

#[test]
fn bad_input_is_refused_with_a_message() {
    let m = blob(2);
    let b = basis(&m, 10);
    let view = (&b).into();
    let e = p2p_to_fmap(&[0, 1], view, view, 5, 5).unwrap_err();
    assert!(e.to_string().contains("point map"), "{e}");
    let e = p2p_to_fmap(&vec![m.n_vertices(); m.n_vertices()], view, view, 5, 5).unwrap_err();
    assert!(e.to_string().contains("vertices"), "{e}");
    let e = match_shapes(&m, view, &m, view, &[], &MatchParams::default()).unwrap_err();
    assert!(e.to_string().contains("eigenpairs"), "{e}");
    let mut p = MatchParams::default();
    p.weights.laplacian = -1.0;
    assert!(p.validate().unwrap_err().to_string().contains("Laplacian"));
    let e = descriptors(view, &DescriptorParams::default(), &[m.n_vertices()]).unwrap_err();
    assert!(e.to_string().contains("landmark"), "{e}");
}
