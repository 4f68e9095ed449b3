//! The answer to a field request: the analysis' field, its critical points and level
//! sets, packed as the page reads them (see the crate documentation for the layout).

use std::time::Instant;

use serde::Serialize;
use spectral_mesh::analysis::{
    Analysis, AnalysisError, CriticalReport, Field, FieldRequest, TruncationHint,
};
use spectral_mesh::fields::harmonic::{Constraint, FloatingComponent};
use spectral_mesh::fields::level_sets::level_set_segments;
use spectral_mesh_render::description::{FieldSummary, FigureDescription, describe};
use spectral_mesh_render::figure::FigureOptions;

/// Where the server time of one field went, in milliseconds.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct Timing {
    /// The field (`Analysis::field_if_ready`).
    pub field: f64,
    /// Critical points and the Euler check.
    pub critical: f64,
    /// Level-set segments.
    pub levels: f64,
    /// Everything before the encoding of the reply.
    pub total: f64,
}

/// The JSON header of a field reply: what a page needs to label and draw the field.
#[derive(Debug, Clone, Serialize)]
pub struct FieldHeader {
    /// Vertices (the number of f32 values that follow the header).
    pub n: usize,
    /// The request kind.
    pub kind: &'static str,
    /// The request with every default resolved (source or anchor filled in): sending it
    /// back gives the same field.
    pub request: FieldRequest,
    /// The vertices the request resolved to.
    #[serde(flatten)]
    pub vertices: ResolvedVertices,
    /// The analysis the field was computed on.
    #[serde(flatten)]
    pub analysis: AnalysisHeader,
    /// The eigenpairs the field used.
    #[serde(flatten)]
    pub basis: BasisUse,
    /// The range of the field's values.
    #[serde(flatten)]
    pub values: ValueRange,
    /// The components without a finite value.
    #[serde(flatten)]
    pub unreachable: Unreachable,
    /// The level sets whose segments follow the values.
    #[serde(flatten)]
    pub level_sets: LevelSets,
    /// Critical points with the Euler check (`null` for categorical fields). A field
    /// constant within the library's relative tolerance has `flat = true` and none.
    pub critical: Option<CriticalReport>,
    /// For heat and diffusion fields: the weight of the first eigenpair left out against
    /// the first varying one, with a warning when truncation dominates
    /// ([`spectral_mesh::analysis::TruncationHint`]); `null` for other fields.
    pub truncation: Option<TruncationHint>,
    /// The figure of this field as the render crate describes it for the options of
    /// the request (colour map, levels, markers, legend, colour bar): what the page
    /// shows and what a download draws.
    pub figure: FigureDescription,
    /// Server time.
    pub timing_ms: Timing,
}

/// The vertices a field request resolved to (part of [`FieldHeader`]).
#[derive(Debug, Clone, Serialize)]
pub struct ResolvedVertices {
    /// The resolved source or anchor, if the kind has one.
    pub source: Option<usize>,
    /// Vertices to mark: source or anchor, constrained vertices, segment maxima.
    pub marks: Vec<usize>,
    /// Resolved constraints of a harmonic map (empty otherwise).
    pub constraints: Vec<Constraint>,
    /// Components a harmonic map left unconstrained (constant, left out of `critical`).
    pub floating: Vec<FloatingComponent>,
}

impl ResolvedVertices {
    /// The vertices of `field`'s resolved request.
    fn of(field: &Field) -> Self {
        Self {
            source: field.request.source(),
            marks: field.marks.clone(),
            constraints: field.constraints.clone(),
            floating: field.floating.clone(),
        }
    }
}

/// The analysis a field was computed on (part of [`FieldHeader`]).
#[derive(Debug, Clone, Serialize)]
pub struct AnalysisHeader {
    /// Discretization.
    pub laplacian: &'static str,
    /// True when the input is a point cloud (its operators are the point-cloud Laplacian,
    /// its level sets and critical points those of the triangle union that Laplacian was
    /// built on).
    pub point_cloud: bool,
    /// A point cloud's mean neighbour spacing ([`Analysis::point_spacing`], in the
    /// input's units), which the page sizes its splats from; `null` for a mesh.
    pub point_spacing: Option<f64>,
    /// True when the field is that of the shape scaled to unit area.
    pub normalized: bool,
}

impl AnalysisHeader {
    /// What a header says of `analysis` and of `field`'s scale.
    fn of(analysis: &Analysis, field: &Field) -> Self {
        Self {
            laplacian: analysis.options().laplacian.name(),
            point_cloud: analysis.is_point_cloud(),
            point_spacing: analysis.point_spacing(),
            normalized: field.normalized,
        }
    }
}

/// The eigenpairs a field used (part of [`FieldHeader`]).
#[derive(Debug, Clone, Serialize)]
pub struct BasisUse {
    /// Eigenpairs used (`null` when no basis was used).
    pub k: Option<usize>,
    /// Eigenpairs the basis held (the first `k` were used).
    pub basis_k: Option<usize>,
    /// The largest eigenvalue used (`lambda_{k-1}`, of the normalised operators when
    /// `normalized`).
    pub lambda_max: Option<f64>,
}

impl BasisUse {
    /// The pairs `field` used of `analysis`' held basis.
    fn of(analysis: &Analysis, field: &Field) -> Self {
        let lambda_max = match (field.k, analysis.held_basis()) {
            (Some(k), Some(b)) if k >= 1 && k <= b.k() => Some(b.values[k - 1]),
            _ => None,
        };
        Self {
            k: field.k,
            basis_k: field.basis_k,
            lambda_max,
        }
    }
}

/// The range of a field's values (part of [`FieldHeader`]).
#[derive(Debug, Clone, Serialize)]
pub struct ValueRange {
    /// True when the values are patch labels (segmentation): no level sets, no critical
    /// points.
    pub categorical: bool,
    /// Smallest finite value.
    pub min: f64,
    /// Largest finite value.
    pub max: f64,
}

impl ValueRange {
    /// The range of `field`'s finite values (`(0, 0)` when none is).
    fn of(field: &Field) -> Self {
        let (min, max) = field.finite_range().unwrap_or((0.0, 0.0));
        let categorical = field.labels.is_some();
        Self {
            categorical,
            min,
            max,
        }
    }
}

/// The components where a field has no finite value (part of [`FieldHeader`]).
#[derive(Debug, Clone, Serialize)]
pub struct Unreachable {
    /// Components a geodesic distance cannot reach (its values there are `+inf`: no
    /// level sets, no critical points); empty otherwise.
    pub unreachable: Vec<usize>,
    /// The library's sentence about them ([`Field::unreachable_message`]), `null` when
    /// every value is finite.
    pub unreachable_message: Option<String>,
}

/// The level sets of a field reply (part of [`FieldHeader`]).
#[derive(Debug, Clone, Serialize)]
pub struct LevelSets {
    /// The iso-values of the level sets whose segments follow, ascending (those of the
    /// figure's description: [`spectral_mesh_render::description`], over its colour
    /// range).
    pub levels: Vec<f64>,
    /// Segments per level set, in the order of `levels`.
    pub level_counts: Vec<u32>,
}

impl LevelSets {
    /// The level sets of `values` on `analysis`' mesh at `levels`, with their segments'
    /// end points (`x1 y1 z1 x2 y2 z2` each, level after level).
    fn extract(analysis: &Analysis, values: &[f64], levels: Vec<f64>) -> (Self, Vec<f32>) {
        let sets = level_set_segments(analysis.mesh(), values, &levels);
        let total: usize = sets.iter().map(Vec::len).sum();
        let mut segments = Vec::with_capacity(6 * total);
        let mut level_counts = Vec::with_capacity(sets.len());
        for set in &sets {
            level_counts.push(set.len() as u32);
            for seg in set {
                for p in seg {
                    segments.extend(p.iter().map(|&x| x as f32));
                }
            }
        }
        let sets = Self {
            levels,
            level_counts,
        };
        (sets, segments)
    }
}

/// A field with everything the page draws.
#[derive(Debug, Clone)]
pub struct FieldReply {
    /// The analysis' field (f64 values, resolved request, marks).
    pub field: Field,
    /// The header.
    pub header: FieldHeader,
    /// Level-set segments, `x1 y1 z1 x2 y2 z2` each, level after level.
    pub segments: Vec<f32>,
}

/// The reply to `request` on `analysis`, described for `figure` (its level sets' segments
/// included when `segments`), from the held basis only: `Ok(None)` when the request needs
/// more eigenpairs than are held.
pub fn field_reply(
    analysis: &Analysis,
    request: &FieldRequest,
    figure: &FigureOptions,
    segments: bool,
) -> Result<Option<FieldReply>, AnalysisError> {
    let start = Instant::now();
    let Some(field) = analysis.field_if_ready(request)? else {
        return Ok(None);
    };
    let t_field = start.elapsed();
    let values = ValueRange::of(&field);
    let critical = if values.categorical {
        None
    } else {
        Some(analysis.field_critical_points(&field)?)
    };
    let t_critical = start.elapsed();
    let summary = FieldSummary::of_field(analysis, &field, critical.as_ref());
    let description = describe(&summary, figure);
    let isos = if segments {
        description.levels.clone()
    } else {
        Vec::new()
    };
    let (level_sets, segments) = LevelSets::extract(analysis, &field.values, isos);
    let t_levels = start.elapsed();
    let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3;
    let header = FieldHeader {
        n: field.values.len(),
        kind: field.request.kind(),
        request: field.request.clone(),
        vertices: ResolvedVertices::of(&field),
        analysis: AnalysisHeader::of(analysis, &field),
        basis: BasisUse::of(analysis, &field),
        values,
        unreachable: Unreachable {
            unreachable: field.unreachable.clone(),
            unreachable_message: field.unreachable_message(),
        },
        level_sets,
        critical,
        truncation: analysis.truncation_hint(&field),
        figure: description,
        timing_ms: Timing {
            field: ms(t_field),
            critical: ms(t_critical - t_field),
            levels: ms(t_levels - t_critical),
            total: ms(start.elapsed()),
        },
    };
    Ok(Some(FieldReply {
        field,
        header,
        segments,
    }))
}

impl FieldReply {
    /// The binary reply: `u32 header_len`, the JSON header padded with spaces to a
    /// multiple of 4 bytes, `f32 values[n]`, `f32 segments[6 * total]`, little-endian.
    pub fn to_bytes(&self) -> Result<Vec<u8>, serde_json::Error> {
        let mut head = serde_json::to_vec(&self.header)?;
        while !head.len().is_multiple_of(4) {
            head.push(b' ');
        }
        let values = &self.field.values;
        let mut buf = Vec::with_capacity(4 + head.len() + 4 * (values.len() + self.segments.len()));
        buf.extend_from_slice(&(head.len() as u32).to_le_bytes());
        buf.extend_from_slice(&head);
        for v in values {
            buf.extend_from_slice(&(*v as f32).to_le_bytes());
        }
        for v in &self.segments {
            buf.extend_from_slice(&v.to_le_bytes());
        }
        Ok(buf)
    }
}

/// The parts of a binary field reply.
#[derive(Debug, Clone)]
pub struct ParsedReply {
    /// The JSON header.
    pub header: serde_json::Value,
    /// `n` values.
    pub values: Vec<f32>,
    /// Level-set segment coordinates, 6 per segment.
    pub segments: Vec<f32>,
}

/// Reads a binary field reply (for tests and clients written in Rust).
pub fn parse_reply(body: &[u8]) -> Result<ParsedReply, String> {
    let word = |i: usize| -> Result<[u8; 4], String> {
        body.get(i..i + 4)
            .and_then(|b| b.try_into().ok())
            .ok_or_else(|| format!("the reply ends at byte {}", body.len()))
    };
    let hl = u32::from_le_bytes(word(0)?) as usize;
    let head = body
        .get(4..4 + hl)
        .ok_or("the reply is shorter than its header")?;
    let header: serde_json::Value =
        serde_json::from_slice(head).map_err(|e| format!("header: {e}"))?;
    let n = header["n"].as_u64().ok_or("the header has no n")? as usize;
    let rest = &body[4 + hl..];
    if !rest.len().is_multiple_of(4) || rest.len() < 4 * n {
        return Err(format!(
            "{} bytes after the header for n = {n} values",
            rest.len()
        ));
    }
    let floats: Vec<f32> = rest
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    let segments = floats[n..].to_vec();
    let mut values = floats;
    values.truncate(n);
    Ok(ParsedReply {
        header,
        values,
        segments,
    })
}
