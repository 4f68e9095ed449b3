//! A point cloud: positions in R^3 and, optionally, one normal per point.
//!
//! The input of the point-cloud Laplacian ([`crate::operators::point_cloud`]). Normals are
//! optional and may be partial: a zero normal means "unknown" (some files, such as a
//! `x y z 0 0 0` export, carry zeros), and the Laplacian then estimates the tangent plane
//! from the neighbours instead.

use thiserror::Error;

use super::{bounding_box, norm, sub};

/// Errors raised when a point cloud is built from raw arrays.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum PointCloudError {
    /// No points.
    #[error("the point cloud is empty")]
    Empty,
    /// A coordinate is NaN or infinite.
    #[error("point {point} has a non-finite coordinate")]
    NonFinite {
        /// Point index.
        point: usize,
    },
    /// A normal component is NaN or infinite.
    #[error("the normal of point {point} has a non-finite component")]
    NonFiniteNormal {
        /// Point index.
        point: usize,
    },
    /// The normals are not one per point.
    #[error("{normals} normals for {points} points")]
    NormalCount {
        /// Number of normals.
        normals: usize,
        /// Number of points.
        points: usize,
    },
}

/// `n` points in R^3 with optional normals (`n` of them when present).
///
/// Construction through [`PointCloud::new`] guarantees at least one point, finite
/// coordinates and finite normals, one per point. Duplicate points and zero normals are
/// legal.
#[derive(Debug, Clone, PartialEq)]
pub struct PointCloud {
    positions: Vec<[f64; 3]>,
    normals: Option<Vec<[f64; 3]>>,
}

impl PointCloud {
    /// Builds a point cloud, checking the invariants listed on [`PointCloud`].
    pub fn new(
        positions: Vec<[f64; 3]>,
        normals: Option<Vec<[f64; 3]>>,
    ) -> Result<Self, PointCloudError> {
        if positions.is_empty() {
            return Err(PointCloudError::Empty);
        }
        if let Some(p) = positions
            .iter()
            .position(|p| p.iter().any(|c| !c.is_finite()))
        {
            return Err(PointCloudError::NonFinite { point: p });
        }
        if let Some(nr) = &normals {
            if nr.len() != positions.len() {
                return Err(PointCloudError::NormalCount {
                    normals: nr.len(),
                    points: positions.len(),
                });
            }
            if let Some(p) = nr.iter().position(|v| v.iter().any(|c| !c.is_finite())) {
                return Err(PointCloudError::NonFiniteNormal { point: p });
            }
        }
        Ok(Self { positions, normals })
    }

    /// Positions, `n` entries.
    pub fn positions(&self) -> &[[f64; 3]] {
        &self.positions
    }

    /// Normals (`n` entries, not necessarily unit, zero = unknown), when the input had them.
    pub fn normals(&self) -> Option<&[[f64; 3]]> {
        self.normals.as_deref()
    }

    /// Number of points `n`.
    pub fn n_points(&self) -> usize {
        self.positions.len()
    }

    /// Number of points whose normal is usable (non-zero); 0 without normals.
    pub fn n_normals(&self) -> usize {
        self.normals
            .as_ref()
            .map_or(0, |nr| nr.iter().filter(|v| norm(**v) > 0.0).count())
    }

    /// The content hash every face uses to name a point cloud: blake3 (64 hex digits) of
    /// the positions as little-endian `f64` (normals are not included). Equal to
    /// [`super::Mesh::content_hash`] of the same positions with no triangles.
    pub fn content_hash(&self) -> String {
        let mut h = blake3::Hasher::new();
        for p in &self.positions {
            for c in p {
                h.update(&c.to_le_bytes());
            }
        }
        h.finalize().to_hex().to_string()
    }

    /// Drops the normals.
    pub fn without_normals(self) -> Self {
        Self {
            positions: self.positions,
            normals: None,
        }
    }

    /// Consumes the cloud and returns its arrays.
    pub fn into_parts(self) -> (Vec<[f64; 3]>, Option<Vec<[f64; 3]>>) {
        (self.positions, self.normals)
    }

    /// Axis-aligned bounding box as `(min, max)`.
    pub fn bounding_box(&self) -> ([f64; 3], [f64; 3]) {
        bounding_box(&self.positions)
    }

    /// Length of the bounding-box diagonal.
    pub fn diagonal(&self) -> f64 {
        let (lo, hi) = self.bounding_box();
        norm(sub(hi, lo))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn construction_checks_what_it_promises() {
        assert_eq!(PointCloud::new(vec![], None), Err(PointCloudError::Empty));
        assert_eq!(
            PointCloud::new(vec![[0.0, f64::NAN, 0.0]], None),
            Err(PointCloudError::NonFinite { point: 0 })
        );
        assert_eq!(
            PointCloud::new(vec![[0.0; 3]; 2], Some(vec![[0.0; 3]])),
            Err(PointCloudError::NormalCount {
                normals: 1,
                points: 2
            })
        );
        assert_eq!(
            PointCloud::new(vec![[0.0; 3]], Some(vec![[f64::INFINITY, 0.0, 0.0]])),
            Err(PointCloudError::NonFiniteNormal { point: 0 })
        );
        let c = PointCloud::new(
            vec![[0.0; 3], [1.0, 2.0, 2.0]],
            Some(vec![[0.0; 3], [0.0, 0.0, 2.0]]),
        )
        .unwrap();
        assert_eq!(c.n_points(), 2);
        assert_eq!(c.n_normals(), 1);
        assert_eq!(c.diagonal(), 3.0);
        assert!(c.without_normals().normals().is_none());
    }
}
