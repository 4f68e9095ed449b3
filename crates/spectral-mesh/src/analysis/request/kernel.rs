//! The heat kernel discretization named in a request.

use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::spectral::heat::KernelKind;

/// A heat kernel discretization (see [`crate::spectral::heat`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Kernel {
    /// `K_t = X D_t X^T B` (the paper's wFEM kernel; conserves the B-mass). Default.
    #[default]
    Wfem,
    /// `K*_t = X D_t X^T D`, D the lumped mass.
    VoronoiCot,
    /// `K~_t = X D_t X^T` (no mass; LaPy's and pyFM's kernel).
    Standard,
}

impl Kernel {
    /// Every kernel, in a stable order.
    pub const ALL: [Kernel; 3] = [Kernel::Wfem, Kernel::VoronoiCot, Kernel::Standard];

    /// The name typed.
    pub fn name(self) -> &'static str {
        match self {
            Kernel::Wfem => "wfem",
            Kernel::VoronoiCot => "voronoi-cot",
            Kernel::Standard => "standard",
        }
    }
}

impl From<Kernel> for KernelKind {
    fn from(k: Kernel) -> Self {
        match k {
            Kernel::Wfem => KernelKind::Wfem,
            Kernel::VoronoiCot => KernelKind::VoronoiCot,
            Kernel::Standard => KernelKind::Standard,
        }
    }
}

impl FromStr for Kernel {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Kernel::ALL
            .into_iter()
            .find(|k| k.name() == s.trim())
            .ok_or_else(|| format!("unknown kernel '{s}': expected wfem, voronoi-cot or standard"))
    }
}
