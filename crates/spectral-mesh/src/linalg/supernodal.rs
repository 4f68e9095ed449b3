//! The supernodal layout of a Cholesky factor and our triangular solves on it.
//!
//! The right-hand sides are gathered into a row-major block (a few columns side by side,
//! permuted), and each supernode's columns are applied to those rows with fixed-width inner
//! loops. Mesh Laplacians give many small supernodes, where this measured 2-3x faster per
//! right-hand side than faer's general dense kernels per supernode (blocks of 8-16, 38k
//! vertices); the factor is streamed once per block of up to 8 right-hand sides.
//!
//! On large factors one solve runs on two threads: the elimination tree is cut
//! ([`TreeSplit`]) into a left part (every supernode before a cut), a right part (the
//! supernodes after the cut that are not ancestors of the left part) and the top (those
//! ancestors). The left and right parts have no supernode in common and no row either but
//! the top's, so they run side by side; the left part's updates of top rows go to a small
//! buffer that is added before the top is solved. The split is a property of the factor,
//! not of the thread count, so a solve gives the same bits on one thread or on many.
//!
//! The sweeps are compiled for the SIMD level pulp detects at run time (AVX2 where
//! present): the whole solve through [`SolveOp`], and each part of a split solve through
//! [`SweepOp`] of its own, since a closure given to `rayon::join` does not inherit the
//! target features of the function it is written in.

use faer::sparse::linalg::cholesky::{SymbolicCholesky, SymbolicCholeskyRaw};

/// Supernodes with at least this many columns are applied column by column (contiguous
/// in L); smaller ones row by row (each scattered row of the right-hand side once).
const ROW_OUTER_MAX: usize = 8;

/// Factors with fewer rows are solved on one thread (the join costs more than it saves).
const SPLIT_MIN_ROWS: usize = 8_192;

/// A split is kept only when it is predicted to take at most this share of the sequential
/// solve's time (predicted: the larger part plus the top, counted in values of L).
const SPLIT_MAX_SHARE: f64 = 0.8;

/// The supernodal layout of the factor, copied out of faer's symbolic structure: supernode
/// `s` holds columns `begin[s]..begin[s + 1]`; its values are a column-major block of
/// `(size + pattern) x size` starting at `val_ptr[s]` (the lower-triangular diagonal block
/// on top, then the rows `row_idx[row_ptr[s]..row_ptr[s + 1]]`, increasing); `fwd[i]` is
/// the original index of permuted row `i`.
#[derive(Debug)]
pub(super) struct Supernodes {
    begin: Vec<usize>,
    row_ptr: Vec<usize>,
    val_ptr: Vec<usize>,
    /// Row indices as `u32`: half the memory of faer's `usize` (1.5M indices at 414k
    /// vertices: 6 MB saved; the solves' time did not change). A factor of more rows than
    /// `u32` holds has no layout and is solved by faer.
    row_idx: Vec<u32>,
    fwd: Vec<usize>,
    /// Columns of the largest supernode (the size of each sweep's scratch).
    max_size: usize,
    split: Option<TreeSplit>,
}

/// A cut of the elimination tree between two threads (see the module's documentation).
/// Supernodes are numbered in a postorder, so every subtree is a range of numbers and the
/// supernodes that straddle the cut before supernode `q` are exactly the ancestors of
/// `q - 1`: those form the top.
#[derive(Debug, PartialEq)]
struct TreeSplit {
    /// The left part is supernodes `0..q`...
    q: usize,
    /// ...which hold columns (and rows) `0..c`.
    c: usize,
    /// The right part: supernodes after `q` that are not in the top, increasing.
    right: Vec<usize>,
    /// The top: the ancestors of supernode `q - 1`, increasing.
    top: Vec<usize>,
    /// The top's columns, increasing: the only rows at or above `c` the left part touches.
    top_cols: Vec<usize>,
    /// For each row `r >= c`: its position in `top_cols` (`u32::MAX` for other rows).
    hi_map: Vec<u32>,
    /// The share of a one-thread solve's time the split solve is predicted to take.
    share: f64,
}

/// `y -= a x`, lane by lane.
#[inline(always)]
fn sub_scaled<const C: usize>(y: &mut [f64; C], a: f64, x: &[f64; C]) {
    for q in 0..C {
        y[q] -= a * x[q];
    }
}

/// The direction of a sweep of the triangular solve.
#[derive(Clone, Copy)]
enum Sweep {
    /// `L y = x`.
    Forward,
    /// `L^T z = y`.
    Backward,
}

/// Where the rows of one part of a solve live: rows below `bound` in `lo` (row `r` at
/// `r - off`), the others in `hi` (row `r` at `hi_map[r - bound]`).
struct Rows<'a, const C: usize> {
    lo: &'a mut [[f64; C]],
    off: usize,
    bound: usize,
    hi: &'a mut [[f64; C]],
    hi_map: &'a [u32],
}

impl<'a, const C: usize> Rows<'a, C> {
    /// Every row in `lo` (row `r` at `r - off`).
    fn all(lo: &'a mut [[f64; C]], off: usize) -> Self {
        Self {
            lo,
            off,
            bound: usize::MAX,
            hi: &mut [],
            hi_map: &[],
        }
    }

    #[inline(always)]
    fn at(&self, r: u32) -> [f64; C] {
        let r = r as usize;
        if r < self.bound {
            self.lo[r - self.off]
        } else {
            self.hi[self.hi_map[r - self.bound] as usize]
        }
    }

    #[inline(always)]
    fn at_mut(&mut self, r: u32) -> &mut [f64; C] {
        let r = r as usize;
        if r < self.bound {
            &mut self.lo[r - self.off]
        } else {
            &mut self.hi[self.hi_map[r - self.bound] as usize]
        }
    }
}

/// Runtime SIMD dispatch of [`Supernodes::solve_block`] (AVX2/AVX-512 when available).
struct SolveOp<'a, const C: usize> {
    sn: &'a Supernodes,
    vals: &'a [f64],
    x: &'a mut [[f64; C]],
    ldlt: bool,
}

impl<const C: usize> pulp::WithSimd for SolveOp<'_, C> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        self.sn.solve_block::<C>(self.vals, self.x, self.ldlt);
    }
}

/// Runtime SIMD dispatch of one [`Supernodes::sweep`], for the two parts of a split
/// solve: they run in closures of `rayon::join`, which are functions of their own and do
/// not inherit the SIMD level [`SolveOp`] was compiled for. Without this their loops ran
/// as SSE2 code; dispatched, the solves of `eigs -k 50` took 0.13 s instead of 0.21 s at
/// 26k vertices and 0.50-0.70 s instead of 0.90-0.99 s at 104k (BENCHMARKS.md).
struct SweepOp<'s, 'r, 'x, const C: usize, I> {
    sn: &'s Supernodes,
    sweep: Sweep,
    vals: &'s [f64],
    nodes: I,
    x: &'r mut Rows<'x, C>,
    top: &'r mut [[f64; C]],
    ldlt: bool,
}

impl<const C: usize, I: Iterator<Item = usize>> pulp::WithSimd for SweepOp<'_, '_, '_, C, I> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        self.sn.sweep(
            self.sweep, self.vals, self.nodes, self.x, self.top, self.ldlt,
        );
    }
}

impl Supernodes {
    /// [`Supernodes::sweep`] compiled for the SIMD level pulp detects (see [`SweepOp`]).
    fn sweep_dispatched<const C: usize>(
        &self,
        (sweep, ldlt): (Sweep, bool),
        vals: &[f64],
        nodes: impl Iterator<Item = usize>,
        x: &mut Rows<'_, C>,
        top: &mut [[f64; C]],
    ) {
        pulp::Arch::new().dispatch(SweepOp {
            sn: self,
            sweep,
            vals,
            nodes,
            x,
            top,
            ldlt,
        });
    }

    /// The layout of a supernodal analysis (`None` for a simplicial one), its solves split
    /// over the elimination tree when the factor is large and a cut pays.
    pub(super) fn from_symbolic(sym: &SymbolicCholesky<usize>) -> Option<Self> {
        Self::build(sym, true)
    }

    /// [`Supernodes::from_symbolic`], with the tree split only when `split` allows it.
    pub(super) fn build(sym: &SymbolicCholesky<usize>, split: bool) -> Option<Self> {
        let SymbolicCholeskyRaw::Supernodal(sn) = sym.raw() else {
            return None;
        };
        let ns = sn.n_supernodes();
        let mut begin = sn.supernode_begin().to_vec();
        begin.push(*sn.supernode_end().last().unwrap_or(&0));
        let fwd = match sym.perm() {
            Some(p) => p.arrays().0.to_vec(),
            None => (0..sym.nrows()).collect(),
        };
        let mut layout = Self {
            begin,
            row_ptr: sn.col_ptr_for_row_idx()[..=ns].to_vec(),
            val_ptr: sn.col_ptr_for_val()[..=ns].to_vec(),
            row_idx: sn
                .row_idx()
                .iter()
                .map(|&r| u32::try_from(r).ok())
                .collect::<Option<_>>()?,
            fwd,
            max_size: 0,
            split: None,
        };
        layout.max_size = (0..ns).map(|s| layout.size(s)).max().unwrap_or(0);
        if split && layout.fwd.len() >= SPLIT_MIN_ROWS {
            layout.split = layout.tree_split();
        }
        Some(layout)
    }

    fn n_supernodes(&self) -> usize {
        self.begin.len() - 1
    }

    fn size(&self, s: usize) -> usize {
        self.begin[s + 1] - self.begin[s]
    }

    fn pattern(&self, s: usize) -> &[u32] {
        &self.row_idx[self.row_ptr[s]..self.row_ptr[s + 1]]
    }

    /// The parent of every supernode in the elimination tree (`None` for a root): the
    /// supernode that holds the first row of its pattern.
    fn parents(&self) -> Vec<Option<usize>> {
        let ns = self.n_supernodes();
        let mut owner = vec![0; self.fwd.len()];
        for s in 0..ns {
            owner[self.begin[s]..self.begin[s + 1]].fill(s);
        }
        (0..ns)
            .map(|s| self.pattern(s).first().map(|&r| owner[r as usize]))
            .collect()
    }

    /// The best cut of the elimination tree for two threads, or `None` when the numbering
    /// is not a postorder or no cut saves enough (see [`SPLIT_MAX_SHARE`]).
    fn tree_split(&self) -> Option<TreeSplit> {
        let ns = self.n_supernodes();
        if ns < 3 {
            return None;
        }
        let parent = self.parents();
        // Work of a supernode: its values (each is used once forward, once backward).
        let work: Vec<f64> = (0..ns)
            .map(|s| (self.size(s) * (self.size(s) + self.pattern(s).len())) as f64)
            .collect();
        // Subtrees must be ranges: the first descendant of `s` is `s + 1 - size of its
        // subtree`, and every parent comes after its children.
        let mut count = vec![1usize; ns];
        let mut first = (0..ns).collect::<Vec<_>>();
        for s in 0..ns {
            if let Some(p) = parent[s] {
                if p <= s {
                    return None;
                }
                count[p] += count[s];
                first[p] = first[p].min(first[s]);
            }
        }
        if (0..ns).any(|s| first[s] + count[s] != s + 1) {
            return None;
        }
        // Work of the strict ancestors of each supernode (parents first).
        let mut above = vec![0.0; ns];
        for s in (0..ns).rev() {
            if let Some(p) = parent[s] {
                above[s] = above[p] + work[p];
            }
        }
        let mut prefix = vec![0.0; ns + 1];
        for s in 0..ns {
            prefix[s + 1] = prefix[s] + work[s];
        }
        let total = prefix[ns];
        let cost = |q: usize| {
            let top = above[q - 1];
            prefix[q].max(total - prefix[q] - top) + top
        };
        let q = (1..ns).min_by(|&a, &b| cost(a).total_cmp(&cost(b)))?;
        let share = cost(q) / total;
        if share > SPLIT_MAX_SHARE {
            return None;
        }
        let mut in_top = vec![false; ns];
        let mut a = parent[q - 1];
        while let Some(p) = a {
            in_top[p] = true;
            a = parent[p];
        }
        let top: Vec<usize> = (q..ns).filter(|&s| in_top[s]).collect();
        let right: Vec<usize> = (q..ns).filter(|&s| !in_top[s]).collect();
        let c = self.begin[q];
        let top_cols: Vec<usize> = top
            .iter()
            .flat_map(|&s| self.begin[s]..self.begin[s + 1])
            .collect();
        let mut hi_map = vec![u32::MAX; self.fwd.len() - c];
        for (t, &j) in top_cols.iter().enumerate() {
            hi_map[j - c] = u32::try_from(t).ok()?;
        }
        Some(TreeSplit {
            q,
            c,
            right,
            top,
            top_cols,
            hi_map,
            share,
        })
    }

    /// Number of row indices (each stored as a `u32`).
    pub(super) fn row_indices(&self) -> usize {
        self.row_idx.len()
    }

    /// The share of a sequential solve's time a split solve is predicted to take (1 when
    /// the factor is solved on one thread).
    pub(super) fn split_share(&self) -> f64 {
        self.split.as_ref().map_or(1.0, |sp| sp.share)
    }

    /// One sweep of the triangular solve over `nodes`: [`Sweep::Forward`], `L y = x` (nodes
    /// increasing; every supernode a node's rows depend on is among the nodes before it or
    /// already applied), or [`Sweep::Backward`], `L^T z = y` (decreasing; every supernode in
    /// a node's pattern among the nodes before it or already applied). With `ldlt` the
    /// factor is `L D L^T` (faer's layout: `L` unit lower triangular, `D` on its
    /// diagonal): the forward sweep does not divide, the backward one first divides each
    /// supernode's own rows by `D`.
    #[inline(always)]
    fn sweep<const C: usize>(
        &self,
        sweep: Sweep,
        vals: &[f64],
        nodes: impl Iterator<Item = usize>,
        x: &mut Rows<'_, C>,
        top: &mut [[f64; C]],
        ldlt: bool,
    ) {
        for s in nodes {
            let f = self.begin[s];
            let size = self.size(s);
            let pat = self.pattern(s);
            let nr = size + pat.len();
            let l = &vals[self.val_ptr[s]..self.val_ptr[s] + nr * size];
            let own = f - x.off..f - x.off + size;
            let top = &mut top[..size];
            top.copy_from_slice(&x.lo[own.clone()]);
            match sweep {
                Sweep::Forward => {
                    for jj in 0..size {
                        let col = &l[jj * nr..jj * nr + size];
                        let mut xj = top[jj];
                        if !ldlt {
                            let inv = 1.0 / col[jj];
                            for v in xj.iter_mut() {
                                *v *= inv;
                            }
                            top[jj] = xj;
                        }
                        for ii in jj + 1..size {
                            let a = col[ii];
                            sub_scaled(&mut top[ii], a, &xj);
                        }
                    }
                    x.lo[own].copy_from_slice(top);
                    if size == 1 {
                        let xj = top[0];
                        for (&r, &a) in pat.iter().zip(&l[1..nr]) {
                            let xi = x.at_mut(r);
                            sub_scaled(xi, a, &xj);
                        }
                    } else if size >= ROW_OUTER_MAX {
                        // Large (dense) supernodes: stream the columns of L contiguously.
                        for (jj, tj) in top.iter().enumerate() {
                            let col = &l[jj * nr + size..(jj + 1) * nr];
                            for (&r, &a) in pat.iter().zip(col) {
                                let xi = x.at_mut(r);
                                sub_scaled(xi, a, tj);
                            }
                        }
                    } else {
                        // Small supernodes: touch each scattered row of x once.
                        for (p, &r) in pat.iter().enumerate() {
                            let mut acc = [0.0; C];
                            for (jj, tj) in top.iter().enumerate() {
                                let a = l[jj * nr + size + p];
                                for q in 0..C {
                                    acc[q] += a * tj[q];
                                }
                            }
                            let xi = x.at_mut(r);
                            for q in 0..C {
                                xi[q] -= acc[q];
                            }
                        }
                    }
                }
                Sweep::Backward => {
                    if ldlt {
                        // `L D L^T`: the pivots `D` sit on the diagonal of the unit `L`.
                        for (jj, tj) in top.iter_mut().enumerate() {
                            let inv = 1.0 / l[jj * nr + jj];
                            for v in tj.iter_mut() {
                                *v *= inv;
                            }
                        }
                    }
                    if size == 1 {
                        let mut acc = top[0];
                        for (&r, &a) in pat.iter().zip(&l[1..nr]) {
                            let xi = x.at(r);
                            sub_scaled(&mut acc, a, &xi);
                        }
                        top[0] = acc;
                    } else if size >= ROW_OUTER_MAX {
                        for (jj, tj) in top.iter_mut().enumerate() {
                            let col = &l[jj * nr + size..(jj + 1) * nr];
                            let mut acc = *tj;
                            for (&r, &a) in pat.iter().zip(col) {
                                let xi = x.at(r);
                                sub_scaled(&mut acc, a, &xi);
                            }
                            *tj = acc;
                        }
                    } else {
                        for (p, &r) in pat.iter().enumerate() {
                            let xi = x.at(r);
                            for (jj, tj) in top.iter_mut().enumerate() {
                                let a = l[jj * nr + size + p];
                                sub_scaled(tj, a, &xi);
                            }
                        }
                    }
                    for jj in (0..size).rev() {
                        let col = &l[jj * nr..jj * nr + size];
                        let mut acc = top[jj];
                        for ii in jj + 1..size {
                            let a = col[ii];
                            sub_scaled(&mut acc, a, &top[ii]);
                        }
                        if !ldlt {
                            let inv = 1.0 / col[jj];
                            for v in acc.iter_mut() {
                                *v *= inv;
                            }
                        }
                        top[jj] = acc;
                    }
                    x.lo[own].copy_from_slice(top);
                }
            }
        }
    }

    /// A block of zeroed rows, one per column of the largest supernode (each thread's
    /// copy of a supernode's own rows).
    fn diagonal_scratch<const C: usize>(&self) -> Vec<[f64; C]> {
        vec![[0.0; C]; self.max_size]
    }

    /// Solves `L L^T y = x` in place for a row-major block `x` of `C` columns (permuted):
    /// on one thread, or split over the tree (see [`TreeSplit`]). Always inlined into
    /// [`SolveOp`], so that it is compiled for the SIMD level pulp detects.
    #[inline(always)]
    fn solve_block<const C: usize>(&self, vals: &[f64], x: &mut [[f64; C]], ldlt: bool) {
        let ns = self.n_supernodes();
        let mut top = self.diagonal_scratch::<C>();
        let Some(sp) = &self.split else {
            self.sweep(
                Sweep::Forward,
                vals,
                0..ns,
                &mut Rows::all(x, 0),
                &mut top,
                ldlt,
            );
            self.sweep(
                Sweep::Backward,
                vals,
                (0..ns).rev(),
                &mut Rows::all(x, 0),
                &mut top,
                ldlt,
            );
            return;
        };
        let mut shared = vec![[0.0; C]; sp.top_cols.len()];
        let mut top_right = self.diagonal_scratch::<C>();
        // Forward: both parts side by side (the left part's updates of top rows go to
        // `shared`, added afterwards), then the top.
        self.sweep_parts(
            (Sweep::Forward, ldlt),
            vals,
            sp,
            x,
            &mut shared,
            [&mut top, &mut top_right],
        );
        for (t, &j) in sp.top_cols.iter().enumerate() {
            for q in 0..C {
                x[j][q] += shared[t][q];
            }
        }
        self.sweep(
            Sweep::Forward,
            vals,
            sp.top.iter().copied(),
            &mut Rows::all(x, 0),
            &mut top,
            ldlt,
        );
        // Backward: the top, then both parts side by side (the left part reads the top's
        // rows from `shared`).
        self.sweep(
            Sweep::Backward,
            vals,
            sp.top.iter().rev().copied(),
            &mut Rows::all(x, 0),
            &mut top,
            ldlt,
        );
        for (t, &j) in sp.top_cols.iter().enumerate() {
            shared[t] = x[j];
        }
        self.sweep_parts(
            (Sweep::Backward, ldlt),
            vals,
            sp,
            x,
            &mut shared,
            [&mut top, &mut top_right],
        );
    }

    /// A sweep over the two parts of `split` side by side, the left part on the rows of
    /// `x` before the split's first column and `shared` (the top's rows), the right part
    /// on the others; `tops` is each part's scratch; `ldlt` as in [`Supernodes::sweep`].
    #[inline(always)]
    fn sweep_parts<const C: usize>(
        &self,
        (sweep, ldlt): (Sweep, bool),
        vals: &[f64],
        split: &TreeSplit,
        x: &mut [[f64; C]],
        shared: &mut [[f64; C]],
        [top_left, top_right]: [&mut [[f64; C]]; 2],
    ) {
        let (left, right) = x.split_at_mut(split.c);
        let mut lo = Rows {
            lo: left,
            off: 0,
            bound: split.c,
            hi: shared,
            hi_map: &split.hi_map,
        };
        let mut hi = Rows::all(right, split.c);
        let right_nodes = split.right.iter().copied();
        let how = (sweep, ldlt);
        match sweep {
            Sweep::Forward => rayon::join(
                || self.sweep_dispatched(how, vals, 0..split.q, &mut lo, top_left),
                || self.sweep_dispatched(how, vals, right_nodes, &mut hi, top_right),
            ),
            Sweep::Backward => rayon::join(
                || self.sweep_dispatched(how, vals, (0..split.q).rev(), &mut lo, top_left),
                || self.sweep_dispatched(how, vals, right_nodes.rev(), &mut hi, top_right),
            ),
        };
    }

    /// Solves for `C` column-major columns of `b` (`n` rows each) in place.
    fn solve_cols<const C: usize>(&self, vals: &[f64], b: &mut [f64], n: usize, ldlt: bool) {
        // The row-major block comes from the per-thread scratch pool (fresh large
        // allocations cost page faults on every call; the pool is capped and released
        // when an eigensolve ends).
        let mut buf = super::scratch::take(n * C);
        let (x, _) = buf.as_chunks_mut::<C>();
        for (i, row) in x.iter_mut().enumerate() {
            let src = self.fwd[i];
            for (q, v) in row.iter_mut().enumerate() {
                *v = b[q * n + src];
            }
        }
        pulp::Arch::new().dispatch(SolveOp {
            sn: self,
            vals,
            x,
            ldlt,
        });
        for (i, row) in x.iter().enumerate() {
            let dst = self.fwd[i];
            for (q, v) in row.iter().enumerate() {
                b[q * n + dst] = *v;
            }
        }
        super::scratch::give(buf);
    }

    /// Whether one solve is split over two threads (then splitting the columns over
    /// threads as well gains little).
    pub(super) fn is_split(&self) -> bool {
        self.split.is_some()
    }

    /// Solves for any number of column-major columns, 8 (then 4, 2, 1) at a time, with
    /// the factor `L L^T` (`ldlt` false) or `L D L^T` (`L` unit lower triangular, the
    /// pivots `D` on its diagonal, as faer stores it).
    pub(super) fn solve_many(&self, vals: &[f64], b: &mut [f64], n: usize, ldlt: bool) {
        let mut rest = b;
        while !rest.is_empty() {
            let c = rest.len() / n;
            let w = if c >= 8 {
                8
            } else if c >= 4 {
                4
            } else if c >= 2 {
                2
            } else {
                1
            };
            let (head, tail) = rest.split_at_mut(n * w);
            match w {
                8 => self.solve_cols::<8>(vals, head, n, ldlt),
                4 => self.solve_cols::<4>(vals, head, n, ldlt),
                2 => self.solve_cols::<2>(vals, head, n, ldlt),
                _ => self.solve_cols::<1>(vals, head, n, ldlt),
            }
            rest = tail;
        }
    }
}
