//! Saving and loading an eigenbasis as a NumPy `.npz` archive, and a cache keyed by the
//! mesh, the discretization and the solver parameters.
//!
//! Arrays in the archive (all readable by `numpy.load`):
//! - `eigenvalues`: `(k,)` float64, ascending;
//! - `eigenvectors`: `(n, k)` float64 (stored in Fortran order), `X^T B X = I`;
//! - `mass_data`, `mass_indices`, `mass_indptr`, `mass_shape`: the mass matrix B in SciPy's
//!   CSC layout (`scipy.sparse.csc_matrix((data, indices, indptr), shape=shape)`), indices
//!   as int64;
//! - `residuals`: `(k,)` float64 relative residuals;
//! - `meta`: a JSON document as a 1-d uint8 array (`json.loads(bytes(f["meta"]))`) with
//!   the Laplacian name, `n`, `k`, the mesh hash and the solver parameters.

use std::io::{Read, Write};
use std::path::Path;

use npyz::WriterBuilder;

use super::eigenbasis::{EigenError, EigenParams, EigenProgress, Eigenbasis, compute_eigenbasis};
use crate::linalg::SparseMatrix;
use crate::mesh::Mesh;
use crate::operators::{Laplacian, Operators};

/// Errors of saving, loading and caching.
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// The archive is not a valid eigenbasis file.
    #[error("{path}: not a valid eigenbasis archive: {reason}")]
    Format {
        /// The file.
        path: String,
        /// What is wrong.
        reason: String,
    },
    /// Computing the basis failed.
    #[error(transparent)]
    Eigen(#[from] EigenError),
}

/// What an archive says about how its basis was made.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BasisMeta {
    /// Format version of the archive (currently 1).
    pub format_version: u32,
    /// The discretization (`fem`, `voronoi-cot`, ...).
    pub laplacian: Laplacian,
    /// Number of vertices.
    pub n: usize,
    /// Number of pairs.
    pub k: usize,
    /// [`Mesh::content_hash`] of the mesh, empty when unknown.
    pub mesh_hash: String,
    /// The solver parameters used.
    pub params: EigenParams,
    /// The program that wrote the file.
    pub generator: String,
    /// The floating-point type of the stored eigenvalues and eigenvectors (`float64`
    /// when absent: archives written before the field existed).
    #[serde(default)]
    pub dtype: BasisDtype,
}

/// The floating-point type the eigenvalues and eigenvectors of an archive are stored in.
/// The basis is always computed in double precision; `Float32` rounds each value once
/// (to nearest, ties to even) when it is written. The mass matrix and the residuals stay
/// float64.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum BasisDtype {
    /// IEEE double precision (NumPy `float64`), the default.
    #[default]
    Float64,
    /// IEEE single precision (NumPy `float32`), as learning pipelines store bases.
    Float32,
}

impl BasisDtype {
    /// The accepted names, for messages.
    pub const NAMES: &'static str = "float64, float32";

    /// The NumPy name (`float64`, `float32`).
    pub fn name(self) -> &'static str {
        match self {
            BasisDtype::Float64 => "float64",
            BasisDtype::Float32 => "float32",
        }
    }

    /// Parses a NumPy name (`float64`/`f8`/`double`, `float32`/`f4`/`single`).
    pub fn parse(s: &str) -> Result<Self, String> {
        match s.trim().to_ascii_lowercase().as_str() {
            "float64" | "f8" | "double" => Ok(BasisDtype::Float64),
            "float32" | "f4" | "single" => Ok(BasisDtype::Float32),
            other => Err(format!(
                "unknown dtype '{other}' (valid: {})",
                BasisDtype::NAMES
            )),
        }
    }

    /// `x` rounded to this type (the identity for `Float64`): what an archive stores.
    pub fn round(self, x: f64) -> f64 {
        match self {
            BasisDtype::Float64 => x,
            BasisDtype::Float32 => x as f32 as f64,
        }
    }
}

impl BasisMeta {
    /// Metadata for `basis` computed on `mesh` with `params`.
    pub fn new(basis: &Eigenbasis, mesh: Option<&Mesh>, params: &EigenParams) -> Self {
        Self {
            format_version: 1,
            laplacian: basis.laplacian,
            n: basis.n,
            k: basis.k(),
            mesh_hash: mesh.map(Mesh::content_hash).unwrap_or_default(),
            params: params.clone(),
            generator: format!("spectral-mesh {}", env!("CARGO_PKG_VERSION")),
            dtype: BasisDtype::Float64,
        }
    }

    /// The same metadata for an archive stored in `dtype` (see [`save_npz`]).
    pub fn with_dtype(self, dtype: BasisDtype) -> Self {
        Self { dtype, ..self }
    }
}

/// Maps an I/O error about `path` to [`StoreError::Io`].
pub(crate) fn io_err(path: &Path) -> impl Fn(std::io::Error) -> StoreError + '_ {
    move |source| StoreError::Io {
        path: path.display().to_string(),
        source,
    }
}

/// A little-endian float64 NumPy `.npy` file of `data` with the given shape, in C order
/// (row-major) or Fortran order (column-major); `numpy.load` reads it.
pub fn npy_f64(data: &[f64], shape: &[u64], fortran: bool) -> std::io::Result<Vec<u8>> {
    let mut buf = Vec::new();
    write_npy_f64(&mut buf, data, shape, fortran)?;
    Ok(buf)
}

/// Streams [`npy_f64`]'s bytes to `out` in large writes, as float32 (each value rounded
/// once) when `dtype` says so. The header is npyz's; the values follow as their
/// little-endian bytes, a buffer at a time (pushed one by one through npyz they took about
/// 20 ms of a 10 MB basis).
fn write_npy(
    out: &mut impl Write,
    data: &[f64],
    shape: &[u64],
    fortran: bool,
    dtype: BasisDtype,
) -> std::io::Result<()> {
    let order = if fortran {
        npyz::Order::Fortran
    } else {
        npyz::Order::C
    };
    match dtype {
        BasisDtype::Float64 => write_le::<f64, f64, 8>(out, data, shape, order, f64::to_le_bytes),
        BasisDtype::Float32 => {
            write_le::<f32, f64, 4>(out, data, shape, order, |x| (x as f32).to_le_bytes())
        }
    }
}

/// npyz's header for an array of `T`, then each value's little-endian bytes (`bytes`), a
/// buffer at a time.
fn write_le<T: npyz::AutoSerialize, S: Copy, const B: usize>(
    out: &mut impl Write,
    data: &[S],
    shape: &[u64],
    order: npyz::Order,
    bytes: impl Fn(S) -> [u8; B],
) -> std::io::Result<()> {
    /// Values per write.
    const CHUNK: usize = 1 << 14;
    out.write_all(&npy_header::<T>(shape, order)?)?;
    let mut buf: Vec<u8> = Vec::with_capacity(B * CHUNK);
    for chunk in data.chunks(CHUNK) {
        buf.clear();
        buf.extend(chunk.iter().flat_map(|&x| bytes(x)));
        out.write_all(&buf)?;
    }
    Ok(())
}

/// The `.npy` header npyz writes for an array of `T` of `shape` in `order`: npyz writes it
/// when its writer begins, and the writer is dropped before any value (its complaint that
/// values are missing, made on drop, is ignored by npyz).
fn npy_header<T: npyz::AutoSerialize>(
    shape: &[u64],
    order: npyz::Order,
) -> std::io::Result<Vec<u8>> {
    let mut header = Vec::new();
    let writer = npyz::WriteOptions::<T>::new()
        .default_dtype()
        .shape(shape)
        .order(order)
        .writer(&mut header)
        .begin_nd()?;
    drop(writer);
    Ok(header)
}

/// Streams [`npy_f64`]'s bytes to `out` (no copy of the data in memory).
pub fn write_npy_f64(
    out: &mut impl Write,
    data: &[f64],
    shape: &[u64],
    fortran: bool,
) -> std::io::Result<()> {
    write_npy(out, data, shape, fortran, BasisDtype::Float64)
}

/// A one-dimensional NumPy `.npy` file of `data` in its native dtype (`<i8` for `i64`,
/// `|u1` for `u8`).
pub(crate) fn npy_1d<T: npyz::AutoSerialize + Copy>(data: &[T]) -> std::io::Result<Vec<u8>> {
    let mut buf = Vec::new();
    let mut w = npyz::WriteOptions::new()
        .default_dtype()
        .shape(&[data.len() as u64])
        .writer(&mut buf)
        .begin_nd()?;
    w.extend(data.iter().copied())?;
    w.finish()?;
    Ok(buf)
}

/// Writes `basis` to `path` as an `.npz` archive (the eigenvectors and the mass stored, the small
/// arrays deflated; see the module documentation for the arrays). The file is written to a temporary name and renamed,
/// so a crash never leaves a truncated archive under `path`.
///
/// The eigenvalues and eigenvectors are stored in `meta.dtype` (float32: each double
/// rounded once; see [`BasisDtype`]).
pub fn save_npz(basis: &Eigenbasis, path: &Path, meta: &BasisMeta) -> Result<(), StoreError> {
    save_npz_as(
        basis,
        path,
        meta,
        (true, &[]),
        meta.dtype,
        crate::io::Durability::WhenReplacing,
    )
}

/// [`save_npz`] with any metadata (`meta`, serialized as the `meta` JSON array), the
/// eigenvectors and mass left out when `vectors` is false (an eigenvalues-only archive,
/// which [`load_npz`] refuses), and `extra` arrays appended: `(name, .npy bytes)` pairs
/// (see [`npy_f64`]), stored as `name.npy`, deflated. The archive is deterministic: the
/// same arguments give the same bytes (entries dated 1980-01-01, as NumPy's `savez`). It
/// is on disk before its name appears ([`crate::io::Durability::Always`]): the batch
/// results are written with it, and their presence says a shape is done.
pub fn save_npz_with(
    basis: &Eigenbasis,
    path: &Path,
    meta: &impl serde::Serialize,
    vectors: bool,
    extra: &[(String, Vec<u8>)],
) -> Result<(), StoreError> {
    save_npz_as(
        basis,
        path,
        meta,
        (vectors, extra),
        BasisDtype::Float64,
        crate::io::Durability::Always,
    )
}

fn save_npz_as(
    basis: &Eigenbasis,
    path: &Path,
    meta: &impl serde::Serialize,
    (vectors, extra): (bool, &[(String, Vec<u8>)]),
    dtype: BasisDtype,
    durability: crate::io::Durability,
) -> Result<(), StoreError> {
    let (n, k) = (basis.n, basis.k());
    let e = io_err(path);
    let meta_json = serde_json::to_vec(meta).map_err(|err| StoreError::Format {
        path: path.display().to_string(),
        reason: err.to_string(),
    })?;
    // The small arrays are compressed; the eigenvectors (n x k doubles, which deflate
    // shrinks by only about a fifth at a cost of seconds per 100 MB) are stored and
    // streamed into the archive without a copy, as NumPy's `savez` stores every array.
    let mut values_npy = Vec::new();
    write_npy(&mut values_npy, &basis.values, &[k as u64], false, dtype).map_err(&e)?;
    let mut small: Vec<(&str, Vec<u8>)> = vec![("eigenvalues", values_npy)];
    small.extend([
        (
            "residuals",
            npy_f64(&basis.residuals, &[basis.residuals.len() as u64], false).map_err(&e)?,
        ),
        ("meta", npy_1d(&meta_json).map_err(&e)?),
    ]);
    crate::io::write_atomic_as(path, durability, |file| {
        let mut npz = NpzWriter::new(std::io::BufWriter::new(file));
        let (first, rest) = small.split_at(1);
        for (name, bytes) in first {
            npz.add(name, bytes, true)?;
        }
        if vectors {
            write_npy(
                npz.start("eigenvectors", false)?,
                &basis.vectors[..n * k],
                &[n as u64, k as u64],
                true,
                dtype,
            )?;
        }
        // The mass arrays (about 7n values and indices) are stored, as NumPy stores them:
        // deflating them took 11% of a whole `eigs` command (26k vertices, k = 50).
        if vectors {
            npz.add_csc("mass", &basis.mass)?;
        }
        let rest = rest.iter().map(|(name, b)| (*name, b.as_slice()));
        let extra = extra.iter().map(|(name, b)| (name.as_str(), b.as_slice()));
        for (name, bytes) in rest.chain(extra) {
            npz.add(name, bytes, true)?;
        }
        npz.finish()
    })
    .map_err(|err| e(err.source))
}

/// An `.npz` archive being written, the one writer of the eigenbasis archives and of the
/// learning cache: every array is an entry `name.npy`, stored or deflated, dated
/// 1980-01-01 (as NumPy's `savez`), so that the same arrays give the same bytes.
pub(crate) struct NpzWriter<W: Write + std::io::Seek> {
    zip: zip::ZipWriter<W>,
}

impl<W: Write + std::io::Seek> NpzWriter<W> {
    /// An empty archive written to `out`.
    pub(crate) fn new(out: W) -> Self {
        Self {
            zip: zip::ZipWriter::new(out),
        }
    }

    /// Starts the entry of the array `name`, deflated or stored; its `.npy` bytes are
    /// written to the returned writer.
    pub(crate) fn start(&mut self, name: &str, deflate: bool) -> std::io::Result<&mut impl Write> {
        let method = if deflate {
            zip::CompressionMethod::Deflated
        } else {
            zip::CompressionMethod::Stored
        };
        let options = zip::write::SimpleFileOptions::default()
            .compression_method(method)
            .last_modified_time(zip::DateTime::default())
            .large_file(true);
        self.zip
            .start_file(format!("{name}.npy"), options)
            .map_err(std::io::Error::other)?;
        Ok(&mut self.zip)
    }

    /// Adds the array `name` from its `.npy` bytes.
    pub(crate) fn add(&mut self, name: &str, npy: &[u8], deflate: bool) -> std::io::Result<()> {
        self.start(name, deflate)?.write_all(npy)
    }

    /// Adds the four stored `.npy` files of a sparse matrix in SciPy's CSC layout, named
    /// `{prefix}_data`, `{prefix}_indices`, `{prefix}_indptr` and `{prefix}_shape` (float64
    /// values, int64 indices; [`NpzReader::square_csc`] reads them back), streamed from the
    /// matrix without a copy (at 414k vertices a copy of the mass matrix as bytes was 70 MB
    /// at the peak of an `eigs` command).
    pub(crate) fn add_csc(&mut self, prefix: &str, m: &SparseMatrix) -> std::io::Result<()> {
        let c = npyz::Order::C;
        let (rows, ptr) = (m.row_idx(), m.col_ptr());
        let as_i64 = |x: usize| (x as i64).to_le_bytes();
        let name = format!("{prefix}_data");
        let (len, vals) = (m.nnz() as u64, m.values());
        write_le::<f64, f64, 8>(self.start(&name, false)?, vals, &[len], c, f64::to_le_bytes)?;
        let name = format!("{prefix}_indices");
        let len = rows.len() as u64;
        write_le::<i64, usize, 8>(self.start(&name, false)?, rows, &[len], c, as_i64)?;
        let name = format!("{prefix}_indptr");
        let len = ptr.len() as u64;
        write_le::<i64, usize, 8>(self.start(&name, false)?, ptr, &[len], c, as_i64)?;
        let shape = npy_1d(&[m.nrows() as i64, m.ncols() as i64])?;
        self.add(&format!("{prefix}_shape"), &shape, false)
    }

    /// Writes the archive's directory and flushes the output.
    pub(crate) fn finish(self) -> std::io::Result<()> {
        let mut out = self.zip.finish().map_err(std::io::Error::other)?;
        out.flush()
    }
}

/// The `meta` array of an `.npz` archive as raw JSON bytes, without reading the other
/// arrays (a quick look at what an archive holds).
pub fn read_npz_meta(path: &Path) -> Result<Vec<u8>, StoreError> {
    NpzReader::open(path)?.meta_bytes()
}

fn format_error(archive: &str, reason: String) -> StoreError {
    StoreError::Format {
        path: archive.to_string(),
        reason,
    }
}

/// An `.npz` archive opened for reading, the one reader of the eigenbasis archives and of
/// the learning cache ([`crate::learning::cache`]). Every array's header is checked
/// against its bytes before it is parsed ([`check_npy_size`]), and every failure is a
/// [`StoreError::Format`] naming the archive.
pub(crate) struct NpzReader<R> {
    zip: zip::ZipArchive<R>,
    name: String,
}

impl NpzReader<std::io::BufReader<std::fs::File>> {
    /// Opens the archive at `path`.
    pub(crate) fn open(path: &Path) -> Result<Self, StoreError> {
        let file = std::fs::File::open(path).map_err(io_err(path))?;
        Self::new(std::io::BufReader::new(file), &path.display().to_string())
    }
}

impl<R: Read + std::io::Seek> NpzReader<R> {
    /// Reads the archive's directory; `name` labels the errors.
    pub(crate) fn new(reader: R, name: &str) -> Result<Self, StoreError> {
        let zip = zip::ZipArchive::new(reader)
            .map_err(|err| format_error(name, format!("not a zip archive ({err})")))?;
        Ok(Self {
            zip,
            name: name.to_string(),
        })
    }

    /// A [`StoreError::Format`] about this archive.
    pub(crate) fn error(&self, reason: String) -> StoreError {
        format_error(&self.name, reason)
    }

    /// The array `name` (the entry `name.npy`), its size checked.
    pub(crate) fn array(
        &mut self,
        name: &str,
    ) -> Result<npyz::NpyFile<std::io::Cursor<Vec<u8>>>, StoreError> {
        let mut bytes = Vec::new();
        let mut entry = self
            .zip
            .by_name(&format!("{name}.npy"))
            .map_err(|_| format_error(&self.name, format!("missing array '{name}'")))?;
        entry
            .read_to_end(&mut bytes)
            .map_err(|err| format_error(&self.name, format!("array '{name}': {err}")))?;
        drop(entry);
        check_npy_size(&bytes).map_err(|reason| self.error(format!("array '{name}': {reason}")))?;
        npyz::NpyFile::new(std::io::Cursor::new(bytes))
            .map_err(|err| self.error(format!("array '{name}': {err}")))
    }

    /// The `meta` array's bytes (a JSON document).
    pub(crate) fn meta_bytes(&mut self) -> Result<Vec<u8>, StoreError> {
        self.array("meta")?
            .into_vec::<u8>()
            .map_err(|err| self.error(format!("array 'meta': {err}")))
    }

    /// The `meta` array parsed.
    pub(crate) fn meta<T: serde::de::DeserializeOwned>(&mut self) -> Result<T, StoreError> {
        serde_json::from_slice(&self.meta_bytes()?)
            .map_err(|err| self.error(format!("meta is not valid JSON ({err})")))
    }

    /// The values of `file` (the array `name`): float64, or float32 widened (an archive
    /// saved with [`BasisDtype::Float32`]).
    pub(crate) fn f64s_of(
        &self,
        file: npyz::NpyFile<std::io::Cursor<Vec<u8>>>,
        name: &str,
    ) -> Result<Vec<f64>, StoreError> {
        let is_f32 = matches!(file.dtype(), npyz::DType::Plain(t)
            if t.type_char() == npyz::TypeChar::Float && t.size_field() == 4);
        let values = if is_f32 {
            file.into_vec::<f32>()
                .map(|v| v.into_iter().map(f64::from).collect())
        } else {
            file.into_vec::<f64>()
        };
        values.map_err(|err| self.error(format!("array '{name}': {err}")))
    }

    /// The values of the array `name` (see [`Self::f64s_of`]).
    pub(crate) fn f64s(&mut self, name: &str) -> Result<Vec<f64>, StoreError> {
        let file = self.array(name)?;
        self.f64s_of(file, name)
    }

    /// An error unless every value is finite.
    pub(crate) fn check_finite(&self, values: &[f64], name: &str) -> Result<(), StoreError> {
        match values.iter().position(|x| !x.is_finite()) {
            Some(i) => Err(self.error(format!("'{name}' entry {i} is {}", values[i]))),
            None => Ok(()),
        }
    }

    /// The int64 array `name` as indices (an error on a negative entry).
    pub(crate) fn indices(&mut self, name: &str) -> Result<Vec<usize>, StoreError> {
        let values = self
            .array(name)?
            .into_vec::<i64>()
            .map_err(|err| self.error(format!("array '{name}': {err}")))?;
        values
            .into_iter()
            .map(|x| {
                usize::try_from(x).map_err(|_| self.error(format!("negative entry in '{name}'")))
            })
            .collect()
    }

    /// The `n x n` sparse matrix written by [`NpzWriter::add_csc`] under `prefix`, checked completely
    /// (shape, index pointer, finite values) before it is built.
    pub(crate) fn square_csc(
        &mut self,
        prefix: &str,
        n: usize,
    ) -> Result<SparseMatrix, StoreError> {
        let data_name = format!("{prefix}_data");
        let data = self.f64s(&data_name)?;
        let indices = self.indices(&format!("{prefix}_indices"))?;
        let indptr = self.indices(&format!("{prefix}_indptr"))?;
        let shape = self.indices(&format!("{prefix}_shape"))?;
        if shape != [n, n] {
            return Err(self.error(format!("'{prefix}' has shape {shape:?}, not {n} x {n}")));
        }
        self.check_finite(&data, &data_name)?;
        // `SparseMatrix::from_csc` slices with each column's range before it has seen the
        // whole index pointer: check it completely first.
        let bad = || {
            self.error(format!(
                "the '{prefix}' arrays are not valid CSC ({prefix}_indptr must rise from 0 to \
                 the number of entries, one per column plus one)"
            ))
        };
        if indptr.len() != n + 1
            || indptr.first() != Some(&0)
            || indptr.last() != Some(&indices.len())
            || indptr.windows(2).any(|w| w[0] > w[1])
            || indices.len() != data.len()
        {
            return Err(bad());
        }
        SparseMatrix::from_csc(n, n, indptr, indices, data).ok_or_else(bad)
    }
}

/// Reads an archive written by [`save_npz`] (or by NumPy with the same arrays; the
/// eigenvectors may be in C or Fortran order).
pub fn load_npz(path: &Path) -> Result<(Eigenbasis, BasisMeta), StoreError> {
    let file = std::fs::File::open(path).map_err(io_err(path))?;
    load_npz_from_reader(std::io::BufReader::new(file), &path.display().to_string())
}

/// [`load_npz`] from any reader (an upload, a buffer); `name` labels the errors. Every
/// array is checked against the others and against its declared size before it is
/// allocated, so a damaged or hostile archive gives [`StoreError::Format`], never a panic
/// or an allocation larger than its own content.
pub fn load_npz_from_reader<R: Read + std::io::Seek>(
    reader: R,
    name: &str,
) -> Result<(Eigenbasis, BasisMeta), StoreError> {
    let mut npz = NpzReader::new(reader, name)?;
    let meta: BasisMeta = npz.meta()?;
    let values = npz.f64s("eigenvalues")?;
    let vf = npz.array("eigenvectors")?;
    let shape = vf.shape().to_vec();
    let order = vf.order();
    if shape.len() != 2 {
        return Err(npz.error(format!("eigenvectors have shape {shape:?}")));
    }
    let (Ok(n), Ok(k)) = (usize::try_from(shape[0]), usize::try_from(shape[1])) else {
        return Err(npz.error(format!("eigenvectors have shape {shape:?}")));
    };
    if n == 0 || k == 0 || n != meta.n || k != meta.k {
        return Err(npz.error(format!(
            "eigenvectors {n} x {k}, but the metadata says n = {}, k = {} (both at least 1)",
            meta.n, meta.k
        )));
    }
    let raw = npz.f64s_of(vf, "eigenvectors")?;
    if k != values.len() || n.checked_mul(k) != Some(raw.len()) {
        return Err(npz.error(format!(
            "eigenvectors {n} x {k} do not match {} eigenvalues",
            values.len()
        )));
    }
    npz.check_finite(&values, "eigenvalues")?;
    npz.check_finite(&raw, "eigenvectors")?;
    let vectors = match order {
        npyz::Order::Fortran => raw,
        npyz::Order::C => {
            let mut v = vec![0.0; n * k];
            for i in 0..n {
                for j in 0..k {
                    v[j * n + i] = raw[i * k + j];
                }
            }
            v
        }
    };
    let mass = npz.square_csc("mass", n)?;
    let residuals = match npz.array("residuals") {
        Ok(f) => npz.f64s_of(f, "residuals")?,
        Err(_) => Vec::new(),
    };
    if !(residuals.is_empty() || residuals.len() == k) {
        return Err(npz.error(format!("{} residuals for {k} eigenpairs", residuals.len())));
    }
    let basis = Eigenbasis {
        laplacian: meta.laplacian,
        n,
        values,
        vectors,
        mass,
        residuals,
    };
    Ok((basis, meta))
}

/// Checks, before `npyz` sees it, that the header of an `.npy` file announces no more data
/// than the file holds (`npyz` multiplies the shape unchecked and reserves that many
/// elements): the shape's product times the item size must fit in the bytes after the
/// header.
fn check_npy_size(bytes: &[u8]) -> Result<(), String> {
    let bad = |m: &str| Err(format!("not a valid .npy array ({m})"));
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return bad("no NUMPY magic");
    }
    let (len, start): (usize, usize) = match bytes[6] {
        1 => (usize::from(u16::from_le_bytes([bytes[8], bytes[9]])), 10),
        2 | 3 if bytes.len() >= 12 => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
        _ => return bad("unknown format version"),
    };
    let Some(header) = bytes.get(start..start.saturating_add(len)) else {
        return bad("truncated header");
    };
    let header = String::from_utf8_lossy(header);
    // npyz parses the header with a backtracking grammar that takes exponential time on
    // some nested or oddly quoted texts (fuzz: a 1.5 kB archive ran for minutes): only the
    // flat dictionary NumPy writes gets through to it.
    let Some((descr, _fortran, dims)) = parse_npy_header(&header) else {
        return bad("the header is not the dictionary NumPy writes");
    };
    // '<f8' -> 8 bytes per element (1 for '|u1').
    let size: u64 = descr
        .chars()
        .skip(2)
        .take_while(char::is_ascii_digit)
        .collect::<String>()
        .parse()
        .unwrap_or(1)
        .max(1);
    let mut count: u64 = 1;
    for d in dims {
        count = match count.checked_mul(d) {
            Some(c) => c,
            None => return bad("the shape's size overflows"),
        };
    }
    let data = (bytes.len() - (start + len)) as u64;
    if count.checked_mul(size).is_none_or(|b| b > data) {
        return Err(format!(
            "the header announces {count} elements of {size} bytes but only {data} bytes follow"
        ));
    }
    Ok(())
}

/// The header of an `.npy` file as NumPy writes it, `{'descr': '<f8', 'fortran_order':
/// False, 'shape': (3, 4), }` padded with spaces and a newline: exactly these three keys
/// (any order, each once, the last comma optional), quoted strings without escapes, a
/// tuple of integers. Returns the descr, the order and the shape.
fn parse_npy_header(header: &str) -> Option<(String, bool, Vec<u64>)> {
    fn quoted(s: &str) -> Option<(&str, &str)> {
        let q = s.chars().next().filter(|c| *c == '\'' || *c == '"')?;
        let s = &s[1..];
        let end = s.find(q)?;
        let v = &s[..end];
        (!v.contains('\\')).then_some((v, &s[end + 1..]))
    }
    let body = header.trim_matches(|c: char| c.is_ascii_whitespace() || c == '\0');
    let body = body.strip_prefix('{')?.strip_suffix('}')?;
    let (mut descr, mut fortran, mut shape) = (None, None, None);
    let mut rest = body.trim_start();
    while !rest.is_empty() {
        let (key, r) = quoted(rest)?;
        let r = r.trim_start().strip_prefix(':')?.trim_start();
        let r = match key {
            "descr" => {
                let (v, r) = quoted(r)?;
                if descr.replace(v.to_string()).is_some() {
                    return None;
                }
                r
            }
            "fortran_order" => {
                let (v, r) = match r.strip_prefix("True") {
                    Some(r) => (true, r),
                    None => (false, r.strip_prefix("False")?),
                };
                if fortran.replace(v).is_some() {
                    return None;
                }
                r
            }
            "shape" => {
                let r = r.strip_prefix('(')?;
                let end = r.find(')')?;
                let mut dims = Vec::new();
                for d in r[..end].split(',').map(str::trim).filter(|d| !d.is_empty()) {
                    dims.push(d.trim_end_matches('L').parse::<u64>().ok()?);
                }
                if shape.replace(dims).is_some() {
                    return None;
                }
                &r[end + 1..]
            }
            _ => return None,
        };
        let r = r.trim_start();
        rest = match r.strip_prefix(',') {
            Some(r) => r.trim_start(),
            None if r.is_empty() => r,
            None => return None,
        };
    }
    Some((descr?, fortran?, shape?))
}

/// The cache file name for a mesh hash, discretization and parameters.
pub fn cache_file_name(hash: &str, laplacian: Laplacian, params: &EigenParams) -> String {
    let pj = serde_json::to_vec(params).unwrap_or_default();
    let ph = blake3::hash(&pj).to_hex();
    format!(
        "{}-{}-k{}-{}.npz",
        &hash[..hash.len().min(16)],
        laplacian.name(),
        params.k,
        &ph.as_str()[..12]
    )
}

/// The cache key of a mesh and its operators: the mesh hash combined with the stiffness
/// matrix (pattern and values), so that operators built from the same triangles with other
/// settings (a point cloud's neighbours or mollification, say) never share a cache file.
pub fn cache_key(mesh_hash: &str, ops: &Operators) -> String {
    let mut h = blake3::Hasher::new();
    h.update(mesh_hash.as_bytes());
    let s = &ops.stiffness;
    for &c in s.col_ptr() {
        h.update(&(c as u64).to_le_bytes());
    }
    for &r in s.row_idx() {
        h.update(&(r as u64).to_le_bytes());
    }
    for &v in s.values() {
        h.update(&v.to_le_bytes());
    }
    h.finalize().to_hex().to_string()
}

/// Returns the basis stored in `cache_dir` for this mesh, discretization and parameters,
/// or computes it (and stores it there). A stored basis is reused only when the mesh hash,
/// the Laplacian, every parameter and the mass matrix (bit for bit: a basis of the shape
/// scaled to unit area is not served for the shape as given) and the stiffness matrix (by
/// its hash in the file name, [`cache_key`]) match; anything unreadable
/// or different is recomputed and overwritten. The boolean is `true` when the basis came from the cache.
pub fn load_or_compute(
    cache_dir: &Path,
    mesh: &Mesh,
    ops: &Operators,
    params: &EigenParams,
    progress: &mut dyn FnMut(EigenProgress),
) -> Result<(Eigenbasis, bool), StoreError> {
    let hash = mesh.content_hash();
    let path = cache_dir.join(cache_file_name(
        &cache_key(&hash, ops),
        ops.laplacian,
        params,
    ));
    if path.is_file()
        && let Ok((basis, meta)) = load_npz(&path)
        && meta.mesh_hash == hash
        && meta.laplacian == ops.laplacian
        && meta.params == *params
        && basis.n == ops.n()
        && basis.k() == params.k
        && basis.mass == ops.mass
    {
        return Ok((basis, true));
    }
    let basis = compute_eigenbasis(ops, params, progress)?;
    std::fs::create_dir_all(cache_dir).map_err(io_err(cache_dir))?;
    let meta = BasisMeta::new(&basis, Some(mesh), params);
    save_npz(&basis, &path, &meta)?;
    Ok((basis, false))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectral::eigenbasis::test_meshes::icosphere;

    /// A 37 x 5 `.npy` written by npyz value by value.
    fn npyz_bytes<T: npyz::AutoSerialize>(
        values: impl Iterator<Item = T>,
        order: npyz::Order,
    ) -> Vec<u8> {
        let mut out = Vec::new();
        let mut w = npyz::WriteOptions::<T>::new()
            .default_dtype()
            .shape(&[37, 5])
            .order(order)
            .writer(&mut out)
            .begin_nd()
            .unwrap();
        w.extend(values).unwrap();
        w.finish().unwrap();
        out
    }

    #[test]
    fn bulk_npy_bytes_equal_npyz_value_by_value() {
        let data: Vec<f64> = (0..37 * 5).map(|i| (i as f64 * 0.37).sin() * 1e3).collect();
        for fortran in [false, true] {
            let order = if fortran {
                npyz::Order::Fortran
            } else {
                npyz::Order::C
            };
            for dtype in [BasisDtype::Float64, BasisDtype::Float32] {
                let mut bulk = Vec::new();
                write_npy(&mut bulk, &data, &[37, 5], fortran, dtype).unwrap();
                let reference = match dtype {
                    BasisDtype::Float64 => npyz_bytes(data.iter().copied(), order),
                    BasisDtype::Float32 => npyz_bytes(data.iter().map(|&x| x as f32), order),
                };
                assert_eq!(bulk, reference, "fortran {fortran}, {dtype:?}");
            }
        }
    }

    fn basis() -> (Mesh, Operators, Eigenbasis, EigenParams) {
        let mesh = icosphere(2, 1.0);
        let ops = Operators::new(&mesh, Laplacian::Fem);
        let params = EigenParams {
            k: 10,
            ..Default::default()
        };
        let b = compute_eigenbasis(&ops, &params, &mut |_| {}).unwrap();
        (mesh, ops, b, params)
    }

    #[test]
    fn round_trip_is_exact() {
        let (mesh, _, b, params) = basis();
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("basis.npz");
        let meta = BasisMeta::new(&b, Some(&mesh), &params);
        save_npz(&b, &p, &meta).unwrap();
        let (b2, meta2) = load_npz(&p).unwrap();
        assert_eq!(meta2, meta);
        assert_eq!(b2.values, b.values);
        assert_eq!(b2.vectors, b.vectors);
        assert_eq!(b2.mass, b.mass);
        assert_eq!(b2.residuals, b.residuals);
        assert_eq!(b2.laplacian, b.laplacian);
        assert_eq!(meta2.mesh_hash.len(), 64);
    }

    #[test]
    fn numpy_reads_the_archive() {
        // $SPECTRAL_MESH_PYTHON, the workspace's .venv, or python3 on the PATH.
        let venv = concat!(env!("CARGO_MANIFEST_DIR"), "/../../.venv/bin/python");
        let candidates = [
            std::env::var("SPECTRAL_MESH_PYTHON").unwrap_or_default(),
            venv.to_string(),
            "python3".to_string(),
        ];
        let python = candidates.iter().filter(|c| !c.is_empty()).find(|c| {
            std::process::Command::new(c.as_str())
                .args(["-c", "import numpy, scipy.sparse"])
                .output()
                .map(|o| o.status.success())
                .unwrap_or(false)
        });
        let Some(python) = python else {
            eprintln!("SKIPPED: no python with numpy + scipy (set SPECTRAL_MESH_PYTHON)");
            return;
        };
        let (_, _, b, params) = basis();
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("basis.npz");
        save_npz(&b, &p, &BasisMeta::new(&b, None, &params)).unwrap();
        let script = r#"
import sys, json, numpy as np, scipy.sparse as sp
f = np.load(sys.argv[1])
X = f["eigenvectors"]; lam = f["eigenvalues"]
B = sp.csc_matrix((f["mass_data"], f["mass_indices"], f["mass_indptr"]), shape=tuple(f["mass_shape"]))
meta = json.loads(bytes(f["meta"]))
assert X.shape == (162, 10) and lam.shape == (10,), (X.shape, lam.shape)
G = X.T @ (B @ X)
assert abs(G - np.eye(10)).max() < 1e-10
assert meta["k"] == 10 and meta["laplacian"] == "fem"
print(repr(float(X[5, 3])), repr(float(lam[4])))
"#;
        let out = std::process::Command::new(python.as_str())
            .args(["-c", script, p.to_str().unwrap()])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let s = String::from_utf8_lossy(&out.stdout);
        let v: Vec<f64> = s.split_whitespace().map(|x| x.parse().unwrap()).collect();
        assert_eq!(v[0], b.vectors[3 * 162 + 5]);
        assert_eq!(v[1], b.values[4]);
    }

    #[test]
    fn cache_reuses_only_matching_bases() {
        let (mesh, ops, _, params) = basis();
        let dir = tempfile::tempdir().unwrap();
        let (b1, cached1) = load_or_compute(dir.path(), &mesh, &ops, &params, &mut |_| {}).unwrap();
        assert!(!cached1);
        let (b2, cached2) = load_or_compute(dir.path(), &mesh, &ops, &params, &mut |_| {}).unwrap();
        assert!(cached2);
        assert_eq!(b1.values, b2.values);
        // Other parameters: recomputed.
        let p2 = EigenParams {
            k: 5,
            ..params.clone()
        };
        let (_, cached3) = load_or_compute(dir.path(), &mesh, &ops, &p2, &mut |_| {}).unwrap();
        assert!(!cached3);
        // Other mesh (moved vertex): recomputed.
        let mut pos = mesh.positions().to_vec();
        pos[0][0] += 1e-3;
        let mesh2 = Mesh::new(pos, mesh.triangles().to_vec()).unwrap();
        assert_ne!(mesh.content_hash(), mesh2.content_hash());
        let ops2 = Operators::new(&mesh2, Laplacian::Fem);
        let (_, cached4) =
            load_or_compute(dir.path(), &mesh2, &ops2, &params, &mut |_| {}).unwrap();
        assert!(!cached4);
        // Other Laplacian: recomputed.
        let ops3 = Operators::new(&mesh, Laplacian::VoronoiCot);
        let (b5, cached5) =
            load_or_compute(dir.path(), &mesh, &ops3, &params, &mut |_| {}).unwrap();
        assert!(!cached5);
        assert_eq!(b5.laplacian, Laplacian::VoronoiCot);
        // Same mesh and mass, another stiffness (as a point cloud's other neighbours or
        // mollification could give): recomputed, not served from the first basis.
        let mut ops4 = Operators::new(&mesh, Laplacian::Fem);
        ops4.stiffness = ops4.stiffness.add_scaled(2.0, &ops.stiffness, 0.0);
        assert_eq!(ops4.mass, ops.mass);
        let (b7, cached7) =
            load_or_compute(dir.path(), &mesh, &ops4, &params, &mut |_| {}).unwrap();
        assert!(!cached7);
        assert!((b7.values[5] - 2.0 * b1.values[5]).abs() < 1e-8 * b1.values[5]);
        // A corrupt cache file is recomputed, not an error.
        let path = dir.path().join(cache_file_name(
            &cache_key(&mesh.content_hash(), &ops),
            Laplacian::Fem,
            &params,
        ));
        std::fs::write(&path, b"garbage").unwrap();
        let (_, cached6) = load_or_compute(dir.path(), &mesh, &ops, &params, &mut |_| {}).unwrap();
        assert!(!cached6);
        assert!(load_npz(&dir.path().join("missing.npz")).is_err());
    }
}
