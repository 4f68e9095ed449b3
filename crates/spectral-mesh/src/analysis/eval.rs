//! Evaluation of a [`FieldRequest`] on an analysis: the only place where a request meets
//! the library's formulas.

use super::request::{Constraints, DistanceSpec, FieldRequest, Signal, SignatureSpec};
use super::{Analysis, AnalysisError, Field};
use crate::fields::harmonic::Constraint;
use crate::fields::segmentation::{SegmentParams, segment};
use crate::geodesic::{GeodesicParams, Source};
use crate::spectral::distances::{
    DistanceError, distances_from, green_row, spectral_function, wfem_diffusion_distances_with,
};
use crate::spectral::embedding::embedding_component;
use crate::spectral::heat::{basis_function, diffuse};
use crate::spectral::signatures::{auto_diffusion, hks, wks};
use crate::spectral::{BasisView, Eigenbasis};

fn vertex(an: &Analysis, key: &'static str, v: usize) -> Result<usize, AnalysisError> {
    if v < an.n() {
        Ok(v)
    } else {
        Err(AnalysisError::VertexOutOfRange {
            key,
            vertex: v,
            n: an.n(),
        })
    }
}

fn per_vertex(an: &Analysis, key: &'static str, v: &[f64]) -> Result<(), AnalysisError> {
    if v.len() == an.n() {
        Ok(())
    } else {
        Err(AnalysisError::LengthMismatch {
            key,
            got: v.len(),
            n: an.n(),
        })
    }
}

/// The indicator of the Euclidean ball of `radius` around `center` (mesh units).
fn ball(an: &Analysis, center: usize, radius: f64) -> Vec<f64> {
    let p = an.mesh().positions();
    let c = p[center];
    p.iter()
        .map(|q| {
            let d2: f64 = (0..3).map(|i| (q[i] - c[i]).powi(2)).sum();
            if d2 <= radius * radius { 1.0 } else { 0.0 }
        })
        .collect()
}

/// The values of a diffusion's signal (`n` entries) and the vertex it is centred on, if any.
pub(super) fn signal_values(
    an: &Analysis,
    signal: &Signal,
) -> Result<(Vec<f64>, Option<usize>), AnalysisError> {
    Ok(match signal {
        Signal::Values(v) => {
            per_vertex(an, "signal", v)?;
            (v.clone(), None)
        }
        Signal::Ball {
            vertex: c, radius, ..
        } => {
            let c = vertex(an, "signal vertex", *c)?;
            (ball(an, c, *radius), Some(c))
        }
        Signal::Impulse(v) => {
            let v = vertex(an, "signal vertex", *v)?;
            let mut e = vec![0.0; an.n()];
            e[v] = 1.0;
            (e, Some(v))
        }
    })
}

/// The values of a signature on the first `k` pairs of `basis` (`None` for given values).
fn signature_values(
    an: &Analysis,
    spec: &SignatureSpec,
    view: Option<BasisView<'_>>,
) -> Result<Vec<f64>, AnalysisError> {
    fn need(v: Option<BasisView<'_>>) -> Result<BasisView<'_>, AnalysisError> {
        v.ok_or(AnalysisError::NoBasis)
    }
    Ok(match spec {
        SignatureSpec::Values(v) => {
            per_vertex(an, "signature", v)?;
            v.clone()
        }
        SignatureSpec::Hks { t } => hks(need(view)?, &[*t], false).swap_remove(0),
        SignatureSpec::Adf { t } => auto_diffusion(need(view)?, *t)?,
        SignatureSpec::Wks { e, sigma } => wks(need(view)?, &[*e], *sigma, false)?.swap_remove(0),
        SignatureSpec::Spectral(f) => spectral_function(need(view)?, f)?,
    })
}

/// Evaluates `req` (validated) with `basis` (holding at least the request's `k` pairs when
/// it needs them).
pub(super) fn evaluate(
    an: &Analysis,
    req: &FieldRequest,
    basis: Option<&Eigenbasis>,
) -> Result<Field, AnalysisError> {
    let k = req.eigenpairs();
    let (view, basis) = match (k, basis) {
        (Some(k), Some(b)) if b.k() >= k => (Some(b.view(k)), Some(b)),
        (Some(k), _) => {
            return Err(AnalysisError::BasisTooSmall {
                k,
                held: basis.map_or(0, |b| b.k()),
            });
        }
        (None, _) => (None, None),
    };
    // Reached only for requests whose `eigenpairs()` is `Some`, where `view` was checked.
    let need = || view.ok_or(AnalysisError::NoBasis);
    let mut request = req.clone();
    let mut marks = Vec::new();
    let mut constraints: Vec<Constraint> = Vec::new();
    let mut labels = None;
    let mut floating = Vec::new();
    let mut unreachable = Vec::new();
    let mut unreachable_vertices = 0;
    let source = |key: &'static str, v: Option<usize>| -> Result<usize, AnalysisError> {
        vertex(an, key, v.unwrap_or_else(|| an.default_source()))
    };
    let values = match req {
        FieldRequest::Harmonic {
            constraints: c,
            order,
        } => {
            let list = c.spec().resolve(an.mesh())?;
            let mut vertices: Vec<usize> = list.iter().map(|c| c.vertex).collect();
            marks = vertices.clone();
            vertices.sort_unstable();
            vertices.dedup();
            let solver = an.harmonic_solver(*order, &vertices)?;
            let f = solver.solve_constraints(&list)?;
            floating = solver.floating_components().to_vec();
            request = FieldRequest::Harmonic {
                constraints: match c {
                    Constraints::Preset(_) => c.clone(),
                    Constraints::List(_) => Constraints::List(list.clone()),
                },
                order: *order,
            };
            constraints = list;
            f
        }
        FieldRequest::Heat {
            anchor, t, kernel, ..
        } => {
            let a = source("anchor", *anchor)?;
            request.set_source(Some(a));
            marks.push(a);
            basis_function(need()?, a, *t, *kernel)?
        }
        FieldRequest::Diffusion {
            signal, t, kernel, ..
        } => {
            let (f, mark) = signal_values(an, signal)?;
            marks.extend(mark);
            diffuse(need()?, &f, *t, *kernel)?
        }
        FieldRequest::Distance {
            source: s,
            distance,
            ..
        } => {
            let s = source("source", *s)?;
            request.set_source(Some(s));
            marks.push(s);
            let v = need()?;
            match distance {
                DistanceSpec::Filter(f) => distances_from(v, s, f)?,
                DistanceSpec::WfemDiffusion { t } => {
                    let bx = an.bx(basis.ok_or(AnalysisError::NoBasis)?);
                    wfem_diffusion_distances_with(v, &bx, s, *t)?
                }
            }
        }
        FieldRequest::SpectralFunction { filter, .. } => spectral_function(need()?, filter)?,
        FieldRequest::Hks { t, scaled, .. } => hks(need()?, &[*t], *scaled).swap_remove(0),
        FieldRequest::Wks {
            energy,
            sigma,
            scaled,
            ..
        } => wks(need()?, &[*energy], *sigma, *scaled)?.swap_remove(0),
        FieldRequest::Adf { t, .. } => auto_diffusion(need()?, *t)?,
        FieldRequest::Segmentation {
            signature,
            persistence,
            ..
        } => {
            let f = signature_values(an, signature, view)?;
            let seg = segment(
                an.mesh(),
                &f,
                SegmentParams {
                    persistence: *persistence,
                },
            )?;
            marks = seg.maxima.clone();
            let v = seg.labels.iter().map(|&l| l as f64).collect();
            labels = Some(seg.labels);
            v
        }
        FieldRequest::Embedding {
            filter, component, ..
        } => {
            let v = need()?;
            let w = filter.weights(v.values).map_err(DistanceError::from)?;
            embedding_component(v, &w, *component)?
        }
        FieldRequest::Eigenfunction { index, .. } => need()?.vector(*index).to_vec(),
        FieldRequest::Green {
            source: s, filter, ..
        } => {
            let s = source("source", *s)?;
            request.set_source(Some(s));
            marks.push(s);
            green_row(need()?, s, filter)?
        }
        FieldRequest::Geodesic {
            source: s,
            sources,
            time_factor,
            convention,
        } => {
            let mut set = Vec::with_capacity(sources.len() + 1);
            if s.is_some() || sources.is_empty() {
                let v = source("source", *s)?;
                request.set_source(Some(v));
                set.push(v);
            }
            for &v in sources {
                set.push(vertex(an, "sources", v)?);
            }
            marks = set.clone();
            marks.sort_unstable();
            marks.dedup();
            let solver = an.geodesic_solver(&GeodesicParams {
                time_factor: *time_factor,
                convention: *convention,
                ..GeodesicParams::default()
            })?;
            let list: Vec<Source> = marks.iter().map(|&v| Source::Vertex(v)).collect();
            let d = solver.distance(&list)?;
            let comp = &an.topology().vertex_component;
            for (v, x) in d.iter().enumerate() {
                if *x == f64::INFINITY {
                    unreachable_vertices += 1;
                    unreachable.push(comp[v]);
                }
            }
            unreachable.sort_unstable();
            unreachable.dedup();
            d
        }
    };
    // A geodesic distance is +inf, and only that, where its sources cannot reach.
    let allowed = |v: f64| v.is_finite() || (unreachable_vertices > 0 && v == f64::INFINITY);
    if let Some(i) = values.iter().position(|&v| !allowed(v)) {
        return Err(AnalysisError::NonFinite {
            kind: req.kind(),
            vertex: i,
        });
    }
    let uses_basis = view.is_some();
    Ok(Field {
        values,
        request,
        marks,
        constraints,
        floating,
        labels,
        unreachable,
        unreachable_vertices,
        k: if uses_basis { k } else { None },
        basis_k: if uses_basis {
            basis.map(|b| b.k())
        } else {
            None
        },
        // A geodesic distance is a length of the mesh as given.
        normalized: an.options().normalize && !matches!(req, FieldRequest::Geodesic { .. }),
    })
}
