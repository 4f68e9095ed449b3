//! What a batch computes for every shape, and the canonical hash of it.

use std::fmt;
use std::str::FromStr;

use crate::analysis::AnalysisOptions;
use crate::analysis::request::DEFAULT_K;
use crate::operators::Laplacian;
use crate::operators::point_cloud::PointCloudParams;
use crate::spectral::eigenbasis::EigenParams;

use super::BatchError;

/// Version of the result layout: part of every parameter hash, bumped when what a result
/// file holds or means changes (so that old results are recomputed, never misread).
pub const RESULT_VERSION: u32 = 1;

/// Times (HKS, ADF) or energies (WKS): `auto:N` from the spectrum, or a list.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case", deny_unknown_fields)]
pub enum Schedule {
    /// `N` values from the spectrum of each shape (pyFM's rules:
    /// [`crate::spectral::signatures::hks_auto_times`] and
    /// [`crate::spectral::signatures::wks_auto_energies`]).
    Auto(usize),
    /// The same values for every shape (times on the shape as analysed: unit area unless
    /// [`SolveParams::normalize`] is off).
    Values(Vec<f64>),
}

impl Schedule {
    /// Number of columns.
    pub fn len(&self) -> usize {
        match self {
            Schedule::Auto(n) => *n,
            Schedule::Values(v) => v.len(),
        }
    }

    /// True when there are no columns.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl fmt::Display for Schedule {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Schedule::Auto(n) => write!(f, "auto:{n}"),
            Schedule::Values(v) => {
                let s: Vec<String> = v.iter().map(|x| format!("{x:?}")).collect();
                f.write_str(&s.join(","))
            }
        }
    }
}

impl FromStr for Schedule {
    type Err = String;

    /// `auto:N` (N >= 1) or a comma-separated list of finite numbers.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let t = s.trim();
        if let Some(n) = t.strip_prefix("auto:").or_else(|| t.strip_prefix("auto=")) {
            let n: usize = n
                .trim()
                .parse()
                .map_err(|_| format!("'{s}': '{n}' is not a count (expected auto:N)"))?;
            if n == 0 {
                return Err(format!("'{s}': at least one value is needed"));
            }
            return Ok(Schedule::Auto(n));
        }
        let mut v = Vec::new();
        for tok in t.split(',').map(str::trim).filter(|x| !x.is_empty()) {
            let x: f64 = tok.parse().map_err(|_| {
                format!("'{s}': '{tok}' is not a number (expected auto:N or a list)")
            })?;
            if !x.is_finite() {
                return Err(format!("'{s}': '{tok}' is not finite"));
            }
            v.push(x);
        }
        if v.is_empty() {
            return Err(format!("'{s}': expected auto:N or a comma-separated list"));
        }
        Ok(Schedule::Values(v))
    }
}

crate::defaults::declare::with_defaults! {
    /// How the eigenbasis of each shape is computed: the discretization, the scale and the
    /// eigensolver's tolerance (the number of pairs is the caller's: [`BatchParams::k`] for the
    /// shapes of a batch, the match's basis size for a pair, see
    /// [`super::pairs::PairParams`]). `Default`: the analysis defaults (fem, unit area, the
    /// eigensolver's tolerance).
    #[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
    #[serde(default)]
    pub struct SolveParams {
        /// The discretization of meshes. Point clouds always use the point-cloud Laplacian
        /// (`robust`, with [`BatchParams::point_cloud`]).
        pub laplacian: Laplacian = AnalysisOptions::default().laplacian,
        /// Target relative residual of every eigenpair.
        pub tolerance: f64 = AnalysisOptions::default().eigen.tolerance,
        /// Analyse each shape scaled to unit total mass (see
        /// [`crate::analysis`]'s scale normalisation): eigenvalues and times comparable across
        /// shapes of different sizes. Off: the operators as assembled (what `eigs` saves).
        pub normalize: bool = AnalysisOptions::default().normalize,
    }
}

impl SolveParams {
    /// Checks the tolerance (the message names it).
    pub fn validate(&self) -> Result<(), BatchError> {
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return Err(BatchError::Parameter {
                key: "tolerance",
                message: format!("{} is not a positive number", self.tolerance),
            });
        }
        Ok(())
    }

    /// The eigensolver parameters of `k` pairs at this tolerance (the library's defaults
    /// otherwise).
    pub fn eigen(&self, k: usize) -> EigenParams {
        EigenParams {
            k,
            tolerance: self.tolerance,
            ..EigenParams::default()
        }
    }

    /// The options of an [`crate::analysis::Analysis`] of a mesh solved for `k` pairs.
    pub fn analysis_options(&self, k: usize) -> AnalysisOptions {
        AnalysisOptions {
            laplacian: self.laplacian,
            normalize: self.normalize,
            eigen: self.eigen(k),
        }
    }
}

/// The per-vertex descriptors saved for every shape (none by default).
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct DescriptorParams {
    /// Heat kernel signature at these times (`n x T` array `hks`).
    pub hks: Option<Schedule>,
    /// Wave kernel signature at these energies (`n x E` array `wks`).
    pub wks: Option<Schedule>,
    /// WKS bandwidth: `None` = from `auto:N`, or 0.5 for a list.
    pub wks_sigma: Option<f64>,
    /// Auto-diffusion function at these times (`n x T` array `adf`).
    pub adf: Option<Schedule>,
    /// Divide HKS by the heat trace and WKS by its normalisation sum.
    pub scaled: bool,
}

impl DescriptorParams {
    /// Checks the schedules and the bandwidth (each message names the parameter).
    pub fn validate(&self) -> Result<(), BatchError> {
        let bad = |key: &'static str, message: String| BatchError::Parameter { key, message };
        for (key, s) in [("hks", &self.hks), ("wks", &self.wks), ("adf", &self.adf)] {
            match s {
                Some(s) if s.is_empty() => {
                    return Err(bad(key, "at least one value is needed".into()));
                }
                Some(Schedule::Values(v)) if v.iter().any(|x| !x.is_finite()) => {
                    return Err(bad(key, "every value must be finite".into()));
                }
                Some(Schedule::Values(v)) if key != "wks" && v.iter().any(|&t| t <= 0.0) => {
                    return Err(bad(key, "times must be > 0".into()));
                }
                _ => {}
            }
        }
        if let Some(s) = self.wks_sigma
            && !(s.is_finite() && s > 0.0)
        {
            return Err(bad("wks_sigma", format!("{s} is not a positive number")));
        }
        Ok(())
    }

    /// The WKS bandwidth for a list of energies (the default when none is given).
    pub fn wks_list_sigma(&self) -> f64 {
        self.wks_sigma
            .unwrap_or(crate::analysis::request::DEFAULT_WKS_SIGMA)
    }
}

crate::defaults::declare::with_defaults! {
    /// What is computed and saved for every shape of a batch. `Default`: 100 FEM pairs of the
    /// shape scaled to unit area at tolerance `1e-10`, the basis saved, no descriptor, no
    /// thumbnail.
    ///
    /// Everything here enters [`BatchParams::hash`]; how the work is run (threads, workers,
    /// the output folder) does not. In JSON the keys of [`SolveParams`] and
    /// [`DescriptorParams`] stand beside the others (flat, as [`BatchParams::KEYS`]); an
    /// unknown key is refused.
    #[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
    #[serde(remote = "Self", default)]
    pub struct BatchParams {
        /// Eigenpairs per shape (the smallest eigenvalues).
        pub k: usize = DEFAULT_K,
        /// How each shape is solved.
        #[serde(flatten)]
        pub solve: SolveParams = SolveParams::default(),
        /// Save the eigenvectors (`n x k`) and the mass matrix; off, the result holds the
        /// eigenvalues (and descriptors) only.
        pub basis: bool = true,
        /// The descriptors saved.
        #[serde(flatten)]
        pub descriptors: DescriptorParams = DescriptorParams::default(),
        /// A PNG thumbnail of this width and height (pixels) showing the first eigenvector
        /// with a non-zero eigenvalue (meshes only).
        pub thumbnail: Option<u32> = None,
        /// Parameters of the point-cloud Laplacian (point-cloud inputs only).
        pub point_cloud: PointCloudParams = PointCloudParams::default(),
        /// Geodesic distances (the heat method with its defaults, in the mesh's units) from
        /// this many farthest-point samples of each mesh, the first at the vertex of largest x:
        /// the `n x N` array `geodesic` (column `j`: the distance from sample `j`, `inf` on
        /// components it cannot reach) and the samples `geodesic_sources`. Meshes only (a
        /// point cloud gets a warning). Left out of the hash when `None`, so that the results
        /// of earlier batches stay valid.
        #[serde(skip_serializing_if = "Option::is_none")]
        pub geodesic: Option<usize> = None,
    }
}

impl serde::Serialize for BatchParams {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        BatchParams::serialize(self, s)
    }
}

impl<'de> serde::Deserialize<'de> for BatchParams {
    /// The keys are checked against [`BatchParams::KEYS`] first (serde cannot refuse
    /// unknown keys beside flattened ones); the error names the unknown key as serde does.
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let map = serde_json::Map::<String, serde_json::Value>::deserialize(d)?;
        if let Some(key) = map.keys().find(|k| !Self::KEYS.contains(&k.as_str())) {
            return Err(D::Error::unknown_field(key, Self::KEYS));
        }
        BatchParams::deserialize(serde_json::Value::Object(map)).map_err(D::Error::custom)
    }
}

/// What the parameter hash is computed from.
#[derive(serde::Serialize)]
struct Canonical<'a> {
    result_version: u32,
    params: &'a BatchParams,
    eigen: &'a EigenParams,
}

impl BatchParams {
    /// The keys of the JSON form, in order.
    pub const KEYS: &'static [&'static str] = &[
        "k",
        "laplacian",
        "tolerance",
        "normalize",
        "basis",
        "hks",
        "wks",
        "wks_sigma",
        "adf",
        "scaled",
        "thumbnail",
        "point_cloud",
        "geodesic",
    ];

    /// Checks every value before any work (each message names the parameter).
    pub fn validate(&self) -> Result<(), BatchError> {
        let bad = |key: &'static str, message: String| BatchError::Parameter { key, message };
        if self.k == 0 {
            return Err(bad("k", "at least one eigenpair is needed".into()));
        }
        self.solve.validate()?;
        self.descriptors.validate()?;
        if let Some(t) = self.thumbnail {
            crate::defaults::values::check_picture_size(t).map_err(|e| bad("thumbnail", e))?;
        }
        if self.geodesic == Some(0) {
            return Err(bad(
                "geodesic",
                "at least one source sample is needed".into(),
            ));
        }
        self.point_cloud
            .validate()
            .map_err(|e| bad("point_cloud", e.to_string()))?;
        Ok(())
    }

    /// The eigensolver parameters every shape is solved with (`k` included).
    pub fn eigen(&self) -> EigenParams {
        self.solve.eigen(self.k)
    }

    /// The canonical hash of the parameters: BLAKE3 (hex, 64 characters) of the JSON of
    /// [`RESULT_VERSION`], these parameters (fields in declaration order, the grouped ones
    /// flat, numbers in shortest round-trip form) and the full eigensolver parameters they
    /// give (seed, method and block size included, so that a change of the library's
    /// defaults recomputes). Equal parameters give equal hashes on every machine.
    pub fn hash(&self) -> String {
        let eigen = self.eigen();
        let c = Canonical {
            result_version: RESULT_VERSION,
            params: self,
            eigen: &eigen,
        };
        // Serializing plain data to a Vec cannot fail; an empty input would still hash.
        let bytes = serde_json::to_vec(&c).unwrap_or_default();
        blake3::hash(&bytes).to_hex().to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schedules_parse_and_print() {
        assert_eq!("auto:16".parse::<Schedule>().unwrap(), Schedule::Auto(16));
        assert_eq!(
            "0.1, 1".parse::<Schedule>().unwrap(),
            Schedule::Values(vec![0.1, 1.0])
        );
        assert_eq!(Schedule::Values(vec![0.1, 1.0]).to_string(), "0.1,1.0");
        for bad in ["auto:0", "a,b", "inf", ""] {
            assert!(bad.parse::<Schedule>().is_err(), "{bad:?}");
        }
    }

    #[test]
    fn hash_is_stable_and_follows_every_parameter() {
        let p = BatchParams::default();
        let h = p.hash();
        assert_eq!(h.len(), 64);
        assert_eq!(h, BatchParams::default().hash());
        // Through JSON and back: the same hash.
        let back: BatchParams = serde_json::from_str(&serde_json::to_string(&p).unwrap()).unwrap();
        assert_eq!(back.hash(), h);
        let variants = [
            BatchParams { k: 99, ..p.clone() },
            BatchParams {
                solve: SolveParams {
                    laplacian: Laplacian::VoronoiCot,
                    ..p.solve.clone()
                },
                ..p.clone()
            },
            BatchParams {
                solve: SolveParams {
                    tolerance: 1e-9,
                    ..p.solve.clone()
                },
                ..p.clone()
            },
            BatchParams {
                solve: SolveParams {
                    normalize: false,
                    ..p.solve.clone()
                },
                ..p.clone()
            },
            BatchParams {
                basis: false,
                ..p.clone()
            },
            BatchParams {
                descriptors: DescriptorParams {
                    hks: Some(Schedule::Auto(16)),
                    ..Default::default()
                },
                ..p.clone()
            },
            BatchParams {
                descriptors: DescriptorParams {
                    hks: Some(Schedule::Values(vec![0.1])),
                    ..Default::default()
                },
                ..p.clone()
            },
            BatchParams {
                thumbnail: Some(128),
                ..p.clone()
            },
        ];
        let mut seen = vec![h];
        for v in &variants {
            let hv = v.hash();
            assert!(!seen.contains(&hv), "{v:?}");
            seen.push(hv);
        }
    }

    #[test]
    fn json_keys_stay_flat_and_unknown_ones_are_refused() {
        let p = BatchParams {
            geodesic: Some(4),
            ..Default::default()
        };
        // The hash's input: every key at the top level, in the order of `KEYS`.
        let text = serde_json::to_string(&p).unwrap();
        let at: Vec<usize> = BatchParams::KEYS
            .iter()
            .map(|k| text.find(&format!("\"{k}\":")).unwrap())
            .collect();
        assert!(at.windows(2).all(|w| w[0] < w[1]), "{text}");
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(v.as_object().unwrap().len(), BatchParams::KEYS.len());
        let back: BatchParams = serde_json::from_value(v).unwrap();
        assert_eq!(back, p);
        let partial: BatchParams =
            serde_json::from_str(r#"{"k": 7, "tolerance": 1e-6, "scaled": true}"#).unwrap();
        assert_eq!(partial.k, 7);
        assert_eq!(partial.solve.tolerance, 1e-6);
        assert!(partial.descriptors.scaled);
        assert_eq!(partial.solve.laplacian, Laplacian::Fem);
        let e = serde_json::from_str::<BatchParams>(r#"{"k": 7, "tolernce": 1e-6}"#).unwrap_err();
        assert!(e.to_string().contains("unknown field `tolernce`"), "{e}");
    }

    #[test]
    fn validation_names_the_parameter() {
        let e = BatchParams {
            k: 0,
            ..Default::default()
        }
        .validate()
        .unwrap_err();
        assert!(e.to_string().contains("k"), "{e}");
        let descriptors = |d: DescriptorParams| BatchParams {
            descriptors: d,
            ..Default::default()
        };
        let e = descriptors(DescriptorParams {
            hks: Some(Schedule::Values(vec![-1.0])),
            ..Default::default()
        })
        .validate()
        .unwrap_err();
        assert!(e.to_string().starts_with("hks"), "{e}");
        assert!(
            descriptors(DescriptorParams {
                wks: Some(Schedule::Values(vec![-1.0])),
                ..Default::default()
            })
            .validate()
            .is_ok()
        );
        let e = BatchParams {
            thumbnail: Some(2),
            ..Default::default()
        }
        .validate()
        .unwrap_err();
        assert!(e.to_string().starts_with("thumbnail"), "{e}");
    }
}
