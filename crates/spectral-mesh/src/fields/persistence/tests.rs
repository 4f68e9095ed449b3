mod reference;

use super::*;
use crate::analysis::{Analysis, AnalysisOptions, FieldRequest, Kernel};
use crate::experiments::harmonic::{HarmonicExperimentParams, harmonic_experiment};
use crate::mesh::Mesh;
use crate::mesh::topology::Topology;
use crate::shapes::build_str;
use crate::test_support::lcg53;

/// `m - s + M` of `cp` (doubled across the boundary when the mesh has one).
fn euler_lhs(cp: &CriticalPoints, mesh: &Mesh) -> (i64, i64) {
    let chi = Topology::new(mesh).euler_characteristic();
    if cp.on_boundary.is_empty() && Topology::new(mesh).boundary_loops.is_empty() {
        cp.euler_check(chi)
    } else {
        cp.euler_check_doubled(chi)
    }
}

/// A constant plus noise above the plateau tolerance (f32 rounding, 1e-9 of the value):
/// the raw classification finds many points, the simplified set none, and the component
/// is quiet. A real field of the same mesh keeps its global minimum and maximum.
#[test]
fn a_constant_plus_rounding_noise_shows_no_critical_point() {
    let sphere = build_str("sphere:res=3").unwrap();
    let n = sphere.n_vertices();
    let mut r = lcg53(7);
    for amplitude in [1e-9, 1e-7] {
        let f: Vec<f64> = (0..n).map(|_| 1.0 + amplitude * r()).collect();
        let p = simplified_critical_points(&sphere, &f).unwrap();
        assert!(p.raw.plateaus.is_empty());
        assert!(
            p.raw.minima.len() + p.raw.maxima.len() > 20,
            "raw: {:?}",
            p.raw
        );
        assert!(
            p.shown.minima.is_empty() && p.shown.maxima.is_empty() && p.shown.saddles.is_empty(),
            "{:?}",
            p.shown
        );
        assert_eq!(p.quiet_components, vec![0]);
        assert!(p.pairs.iter().all(|q| q.hidden));
        // The raw set still satisfies the Euler check.
        let (lhs, rhs) = euler_lhs(&p.raw, &sphere);
        assert_eq!(lhs, rhs);
    }
    // The same noise on a field of range 1: one minimum, one maximum, nothing else.
    let f: Vec<f64> = sphere
        .positions()
        .iter()
        .map(|q| q[2] + 1e-6 * r())
        .collect();
    let p = simplified_critical_points(&sphere, &f).unwrap();
    assert_eq!(
        (
            p.shown.minima.len(),
            p.shown.maxima.len(),
            p.shown.saddle_count()
        ),
        (1, 1, 0)
    );
    assert!(p.quiet_components.is_empty());
    let zmin = (0..n).min_by(|&a, &b| f[a].total_cmp(&f[b])).unwrap();
    assert_eq!(p.shown.minima, vec![zmin]);
    let ess: Vec<&PersistencePair> = p.pairs.iter().filter(|q| q.saddle.is_none()).collect();
    assert_eq!(ess.len(), 2);
    assert!(ess.iter().all(|q| !q.hidden && q.persistence > 1.9));
}

/// The pairing itself on a hand-made field: two bumps on a sphere, one tall and one low,
/// over a gentle tilt (`1e-3 z`, so no ties); the low bump's maximum is paired with a
/// saddle between the bumps and has about the persistence of its height.
#[test]
fn two_bumps_pair_the_lower_maximum_with_a_saddle_between() {
    let sphere = build_str("sphere:res=4").unwrap();
    let bump = |p: &[f64; 3], c: [f64; 3], h: f64| {
        let d2 = (p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2);
        h * (-d2 / 0.1).exp()
    };
    let pos = sphere.positions();
    for (low, expect_hidden) in [(0.3, false), (0.004, true)] {
        let f: Vec<f64> = pos
            .iter()
            .map(|p| bump(p, [1.0, 0.0, 0.0], 1.0) + bump(p, [-1.0, 0.0, 0.0], low) + 1e-3 * p[2])
            .collect();
        let p = simplified_critical_points(&sphere, &f).unwrap();
        let low_max = *p
            .raw
            .maxima
            .iter()
            .min_by(|&&a, &&b| pos[a][0].total_cmp(&pos[b][0]))
            .unwrap();
        assert!(pos[low_max][0] < -0.9, "{:?}", p.raw);
        let q = p.pairs.iter().find(|q| q.extremum == low_max).unwrap();
        assert_eq!(q.kind, ExtremumKind::Maximum);
        let s = q.saddle.expect("the low bump is not essential");
        assert!(p.raw.saddles.iter().any(|x| x.0 == s));
        assert!((q.persistence - (f[q.extremum] - f[s])).abs() < 1e-15);
        assert!(
            (q.persistence - low).abs() < 0.1 * low + 2e-3,
            "{} vs {low}",
            q.persistence
        );
        assert_eq!(q.hidden, expect_hidden);
        let shown = (
            p.shown.minima.len(),
            p.shown.maxima.len(),
            p.shown.saddle_count(),
        );
        assert_eq!(shown, if expect_hidden { (1, 1, 0) } else { (1, 2, 1) });
        let (lhs, rhs) = euler_lhs(&p.shown, &sphere);
        assert_eq!(lhs, rhs);
    }
}

/// The heat kernel at a small time on the genus-3 surface: the truncated series ripples
/// where the heat is tiny and the raw classification marks them; the simplified set is
/// the minimal one (the maximum at the source, one minimum, the 2g = 6 saddles of the
/// handles), every shown maximum sits where the field is large, and every pair hidden is
/// tiny against the field's range.
#[test]
fn the_heat_kernel_at_small_t_on_the_3torus_shows_only_significant_markers() {
    let an = Analysis::new(
        build_str("3torus:res=2").unwrap(),
        AnalysisOptions {
            normalize: true,
            ..Default::default()
        },
    );
    let field = an
        .field(&FieldRequest::Heat {
            anchor: None,
            t: 0.01,
            kernel: Kernel::Wfem,
            k: 100,
        })
        .unwrap();
    let f = &field.values;
    let rep = an.field_critical_points(&field).unwrap();
    let (lo, hi) = f
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    assert!(
        rep.raw.counts.minima + rep.raw.counts.maxima > 10,
        "raw {:?}",
        rep.raw
    );
    assert_eq!(
        (rep.counts.minima, rep.counts.maxima, rep.counts.saddles),
        (1, 1, 6),
        "{rep:?}"
    );
    assert_eq!(rep.points.maxima, field.marks);
    assert!(rep.check.holds && rep.raw.check.holds);
    assert_eq!(rep.check.lhs, -4);
    assert_eq!(
        rep.hidden.minima + rep.hidden.maxima,
        rep.raw.counts.minima + rep.raw.counts.maxima - 2
    );
    for q in &rep.pairs {
        if q.hidden {
            assert!(q.persistence < 0.01 * (hi - lo));
        }
    }
    assert!(rep.points.maxima.iter().all(|&v| f[v] > 0.5 * hi));
}

/// The paper's harmonic maps (Figs. 2, 3: 2, 4 and 6 constraints at the extreme vertices)
/// keep every critical point: their pairs are far above the threshold.
#[test]
fn the_papers_harmonic_maps_keep_all_their_critical_points() {
    for shape in ["torus:res=3", "3torus:res=2", "sphere:res=3"] {
        let mesh = build_str(shape).unwrap();
        let finder = CriticalPointFinder::new(&mesh);
        for run in harmonic_experiment(&mesh, &HarmonicExperimentParams::default()).unwrap() {
            let p = persistence(&finder, &run.field, run.critical.clone()).unwrap();
            assert_eq!(p.shown, p.raw, "{shape} with {} constraints", run.count);
            assert!(p.pairs.iter().all(|q| !q.hidden));
        }
    }
}

/// Hiding pairs keeps the Euler characteristic: smooth fields plus noise of several sizes
/// on closed and bordered meshes (doubled check) and a mesh of two components.
#[test]
fn the_euler_check_holds_for_the_raw_and_the_simplified_sets() {
    let meshes = [
        "irregular-torus:res=3",
        "3torus:res=2",
        "sphere:res=3",
        "disk:res=3",
        "irregular-sphere:res=3",
    ];
    let mut r = lcg53(99);
    let mut hidden_any = 0;
    for shape in meshes {
        let Ok(mesh) = build_str(shape) else {
            continue;
        };
        let finder = CriticalPointFinder::new(&mesh);
        for amplitude in [0.0, 1e-4, 3e-3, 2e-2, 0.3] {
            for rule in [BoundaryRule::Double, BoundaryRule::LowerLink] {
                let f: Vec<f64> = mesh
                    .positions()
                    .iter()
                    .map(|p| (3.0 * p[0]).sin() + p[1] * p[2] + amplitude * r())
                    .collect();
                let raw = finder.find(&f, rule).unwrap();
                let p = persistence(&finder, &f, raw).unwrap();
                let chi = Topology::new(&mesh).euler_characteristic();
                let check = |cp: &CriticalPoints| match rule {
                    BoundaryRule::Double => euler_lhs(cp, &mesh),
                    BoundaryRule::LowerLink => cp.euler_check(chi),
                };
                let (a, b) = check(&p.raw);
                let (c, d) = check(&p.shown);
                assert_eq!((a - b, c - d), (0, 0), "{shape} noise {amplitude} {rule:?}");
                hidden_any += p.hidden_minima() + p.hidden_maxima();
                if Topology::new(&mesh).boundary_loops.is_empty() {
                    assert_eq!(
                        p.hidden_minima() + p.hidden_maxima(),
                        p.hidden_saddles(),
                        "{shape} {amplitude}: a hidden extremum takes one saddle with it"
                    );
                }
                // Every hidden pair is below the threshold.
                for q in &p.pairs {
                    if q.hidden {
                        assert!(q.persistence < p.thresholds.threshold);
                    }
                }
            }
        }
    }
    assert!(hidden_any > 20);
}

/// Meshes for the comparison with the reference: closed (genus 0, 1, 3), bordered, two
/// components, a non-manifold vertex (two fans sharing it) and a vertex no triangle uses.
fn comparison_meshes() -> Vec<Mesh> {
    let mut meshes: Vec<Mesh> = [
        "irregular-torus:res=3",
        "3torus:res=2",
        "sphere:res=3",
        "disk:res=3",
        "irregular-sphere:res=3",
    ]
    .iter()
    .map(|s| build_str(s).unwrap())
    .collect();
    // Two fans sharing vertex 0, and vertex 11 unused.
    let (mut p, t) = crate::test_support::two_fans();
    p.push([5.0, 5.0, 5.0]);
    meshes.push(Mesh::new(p, t).unwrap());
    // Two components: a sphere and a disk side by side.
    let a = build_str("sphere:res=2").unwrap();
    let b = build_str("disk:res=2").unwrap();
    let na = a.n_vertices();
    let mut p = a.positions().to_vec();
    p.extend(b.positions().iter().map(|q| [q[0] + 3.0, q[1], q[2]]));
    let mut t = a.triangles().to_vec();
    t.extend(
        b.triangles()
            .iter()
            .map(|q| [q[0] + na, q[1] + na, q[2] + na]),
    );
    meshes.push(Mesh::new(p, t).unwrap());
    meshes
}

/// Fields with what can break a pairing: smooth, noise, values from three levels (many
/// ties, broken by index), steps below the rounding of the classification (ties after
/// it), NaNs and infinities, a constant.
fn comparison_fields(mesh: &Mesh, next: &mut impl FnMut() -> f64) -> Vec<Vec<f64>> {
    let pos = mesh.positions();
    (0..7)
        .map(|round| {
            pos.iter()
                .map(|q| {
                    let r = next();
                    match round {
                        0 => (3.0 * q[0]).sin() + q[1] * q[2] + 0.05 * r,
                        1 => r,
                        2 => (r * 3.0).floor(),
                        3 => 1.0 + 1e-12 * (r * 4.0).floor() + q[2],
                        4 if r < 0.15 => f64::NAN,
                        5 if r < 0.1 => f64::INFINITY,
                        5 if r < 0.2 => f64::NEG_INFINITY,
                        6 => 2.5,
                        _ => q[0] + 0.3 * r,
                    }
                })
                .collect()
        })
        .collect()
}

/// The two sweeps give what the first implementation (kept in `reference`)
/// gave, pair for pair, on every mesh and field of the comparison; so does the whole
/// result (NaN persistences compared through their printed form).
#[test]
fn the_fast_pairing_agrees_with_the_reference() {
    let mut next = crate::test_support::lcg(2026);
    let mut pairs_seen = 0;
    for mesh in comparison_meshes() {
        let finder = CriticalPointFinder::new(&mesh);
        for f in comparison_fields(&mesh, &mut next) {
            let keys = sort_keys(&f);
            let local = local_order(&finder, &keys);
            let mut slow_order = reference::order(&finder, &f);
            for down in [false, true] {
                let (mut pairs, essential) = sweep(&finder, &keys, &local, down);
                if down {
                    slow_order.reverse();
                }
                let (mut want, want_essential) =
                    reference::sweep(&finder, &slow_order, finder.n_vertices());
                if down {
                    slow_order.reverse();
                }
                pairs.sort_unstable();
                want.sort_unstable();
                assert_eq!(pairs, want, "down {down}");
                assert_eq!(essential, want_essential, "down {down}");
                pairs_seen += pairs.len();
            }
            for rule in [BoundaryRule::Double, BoundaryRule::LowerLink] {
                let raw = finder.find(&f, rule).unwrap();
                let got = persistence(&finder, &f, raw.clone()).unwrap();
                let want = reference::persistence(&finder, &f, raw).unwrap();
                assert_eq!(format!("{got:?}"), format!("{want:?}"), "{rule:?}");
            }
        }
    }
    assert!(pairs_seen > 1000, "{pairs_seen}");
}
