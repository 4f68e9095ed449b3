//! The paper's `Harmonic_function` experiment (Figs. 2, 3): harmonic maps with 2, 4 and 6
//! Dirichlet constraints at the extreme vertices along x, y, z, their critical points, the
//! Euler check, and how much each map changes near the previous constraints (the locality
//! property).
//!
//! The library part only computes; writing `harmonic-field-i.txt`, `.wrl` and `.png` is the
//! caller's job.

use crate::fields::critical_points::{CriticalPoints, CriticalPointsError, critical_points};
use crate::fields::harmonic::{
    Constraint, ConstraintSpec, HarmonicError, harmonic_map_with_operators, max_change_near,
};
use crate::mesh::Mesh;
use crate::mesh::topology::Topology;
use crate::operators::{Laplacian, Operators};

/// Errors of the experiment.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum HarmonicExperimentError {
    /// Choosing constraints or solving failed.
    #[error(transparent)]
    Harmonic(#[from] HarmonicError),
    /// Classifying critical points failed.
    #[error(transparent)]
    CriticalPoints(#[from] CriticalPointsError),
}

crate::defaults::declare::with_defaults! {
    /// Parameters; `Default` is the executable paper's (2, 4, 6 constraints, harmonic, FEM).
    #[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
    pub struct HarmonicExperimentParams {
        /// Numbers of default constraints, each 2, 4 or 6, one map per entry.
        pub constraint_counts: Vec<usize> = vec![2, 4, 6],
        /// 1 = harmonic, 2 = bi-harmonic.
        pub order: u32 = 1,
        /// The discretization.
        pub laplacian: Laplacian = Laplacian::Fem,
        /// Rings around the previous map's constraints over which the change is measured.
        pub locality_rings: usize = 2,
    }
}

/// One map of the experiment.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct HarmonicRun {
    /// Number of default constraints requested.
    pub count: usize,
    /// The constraints actually used (after merging a vertex picked twice).
    pub constraints: Vec<Constraint>,
    /// The field, `n` values.
    pub field: Vec<f64>,
    /// Its critical points (doubling rule on boundaries).
    pub critical: CriticalPoints,
    /// `(m - s + M, chi)` for closed meshes, the doubled count `(.., 2 chi)` otherwise.
    pub euler: (i64, i64),
    /// Largest change from the previous map within `locality_rings` rings of the previous
    /// map's constraints (`None` for the first map).
    pub change_near_previous: Option<f64>,
    /// Largest change from the previous map anywhere (`None` for the first map).
    pub change_anywhere: Option<f64>,
}

/// Runs the experiment on `mesh`.
pub fn harmonic_experiment(
    mesh: &Mesh,
    params: &HarmonicExperimentParams,
) -> Result<Vec<HarmonicRun>, HarmonicExperimentError> {
    let ops = Operators::new(mesh, params.laplacian);
    let topo = Topology::new(mesh);
    let chi = topo.euler_characteristic();
    let closed = topo.boundary_loops.is_empty();
    let mut runs: Vec<HarmonicRun> = Vec::with_capacity(params.constraint_counts.len());
    for &count in &params.constraint_counts {
        let constraints = ConstraintSpec::Extremes(count).resolve(mesh)?;
        let field = harmonic_map_with_operators(mesh, &ops, &constraints, params.order)?;
        let critical = critical_points(mesh, &field)?;
        let euler = if closed {
            critical.euler_check(chi)
        } else {
            critical.euler_check_doubled(chi)
        };
        let (near, anywhere) = match runs.last() {
            Some(prev) => {
                let seeds: Vec<usize> = prev.constraints.iter().map(|c| c.vertex).collect();
                let near =
                    max_change_near(mesh, &prev.field, &field, &seeds, params.locality_rings);
                let all = prev
                    .field
                    .iter()
                    .zip(&field)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max);
                (Some(near), Some(all))
            }
            None => (None, None),
        };
        runs.push(HarmonicRun {
            count,
            constraints,
            field,
            critical,
            euler,
            change_near_previous: near,
            change_anywhere: anywhere,
        });
    }
    Ok(runs)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A torus on a staggered grid (near-equilateral triangles).
    fn torus(nu: usize, nv: usize) -> Mesh {
        let mut p = Vec::new();
        for j in 0..nv {
            let v = std::f64::consts::TAU * j as f64 / nv as f64;
            for i in 0..nu {
                let s = if j % 2 == 1 { 0.5 } else { 0.0 };
                let u = std::f64::consts::TAU * (i as f64 + s) / nu as f64;
                p.push([
                    (3.0 + v.cos()) * u.cos(),
                    (3.0 + v.cos()) * u.sin(),
                    v.sin(),
                ]);
            }
        }
        let id = |j: usize, i: usize| (j % nv) * nu + (i % nu);
        let mut t = Vec::new();
        for j in 0..nv {
            for i in 0..nu {
                if j % 2 == 0 {
                    t.push([id(j, i), id(j, i + 1), id(j + 1, i)]);
                    t.push([id(j + 1, i), id(j, i + 1), id(j + 1, i + 1)]);
                } else {
                    t.push([id(j, i), id(j, i + 1), id(j + 1, i + 1)]);
                    t.push([id(j + 1, i), id(j, i), id(j + 1, i + 1)]);
                }
            }
        }
        Mesh::new(p, t).unwrap()
    }

    #[test]
    fn paper_defaults_on_a_torus() {
        let m = torus(40, 14);
        let runs = harmonic_experiment(&m, &HarmonicExperimentParams::default()).unwrap();
        assert_eq!(runs.len(), 3);
        for r in &runs {
            assert_eq!(r.euler.0, r.euler.1);
            assert_eq!(
                r.critical.minima.len() + r.critical.maxima.len(),
                r.constraints.len()
            );
        }
        assert_eq!(runs[0].critical.saddle_count(), 2);
        // Locality: near the old constraints the map changes less than elsewhere.
        let (near, all) = (
            runs[1].change_near_previous.unwrap(),
            runs[1].change_anywhere.unwrap(),
        );
        assert!(near < all, "{near} vs {all}");
    }
}
