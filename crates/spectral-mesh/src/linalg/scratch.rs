//! Per-thread reuse of large temporary buffers. The eigensolver needs several `n x c`
//! temporaries per step; fresh allocations of that size come back from the system as new,
//! zeroed pages (page faults), which measured as a tenth of the solver's time.
//!
//! Two kinds: a pool of column-major blocks ([`take`], [`give`]), and one row-major buffer
//! per thread for the sparse products ([`with_row_buffer`]). [`release_all`] frees both on
//! every thread. This module depends on nothing else of `linalg`.

use std::cell::RefCell;

thread_local! {
    static POOL: RefCell<Vec<Vec<f64>>> = const { RefCell::new(Vec::new()) };
    /// Row-major copy of the input block of a sparse product on this thread (reused).
    static ROWS: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
}

/// Buffers kept per thread at most.
const KEEP: usize = 8;
/// Entries kept per thread at most (64 MiB of f64): returns beyond that are freed. The
/// solver also calls [`release`] on its own thread when it ends; rayon's worker threads keep
/// at most this much each.
const KEEP_ENTRIES: usize = 8 << 20;

/// A zeroed buffer of `len` entries, reusing a returned one when possible.
pub(crate) fn take(len: usize) -> Vec<f64> {
    let mut v = POOL
        .with(|p| {
            let mut p = p.borrow_mut();
            // The smallest buffer that is large enough, else the largest one.
            let pos = p
                .iter()
                .enumerate()
                .filter(|(_, b)| b.capacity() >= len)
                .min_by_key(|(_, b)| b.capacity())
                .map(|(i, _)| i)
                .or_else(|| {
                    p.iter()
                        .enumerate()
                        .max_by_key(|(_, b)| b.capacity())
                        .map(|(i, _)| i)
                });
            pos.map(|i| p.swap_remove(i))
        })
        .unwrap_or_default();
    v.clear();
    v.resize(len, 0.0);
    v
}

/// Returns a buffer for reuse by [`take`] on this thread.
pub(crate) fn give(v: Vec<f64>) {
    POOL.with(|p| {
        let mut p = p.borrow_mut();
        let held: usize = p.iter().map(|b| b.capacity()).sum();
        if held + v.capacity() > KEEP_ENTRIES {
            return;
        }
        if p.len() < KEEP {
            p.push(v);
        } else if let Some(small) = p
            .iter_mut()
            .min_by_key(|b| b.capacity())
            .filter(|s| s.capacity() < v.capacity())
        {
            *small = v;
        }
    });
}

/// Frees this thread's buffers (called when a solve ends, so that a long-running process
/// such as the web server does not hold them).
pub(crate) fn release() {
    // `try_`: [`release_all`] may run here from another solve's broadcast (never while
    // `take` or `give` hold the pool, but a panic there would be the wrong answer).
    POOL.with(|p| {
        if let Ok(mut p) = p.try_borrow_mut() {
            p.clear();
        }
    });
}

/// Runs `f` on this thread's row-major buffer, grown to at least `len` values (its first
/// `len` values are passed; their content is left from earlier use). Kept until
/// [`release_all`]; the sparse products hold it across a parallel loop.
pub(crate) fn with_row_buffer<R>(len: usize, f: impl FnOnce(&mut [f64]) -> R) -> R {
    ROWS.with(|cell| {
        let mut buf = cell.borrow_mut();
        if buf.len() < len {
            buf.resize(len, 0.0);
        }
        f(&mut buf[..len])
    })
}

/// Frees this thread's row buffer (see [`with_row_buffer`]), unless the thread is using
/// it: a sparse product holds it across a parallel loop, during which the thread may run
/// the broadcast of another solve's [`release_all`] (two solves side by side, as in a
/// study).
fn release_rows() {
    ROWS.with(|cell| {
        if let Ok(mut buf) = cell.try_borrow_mut() {
            *buf = Vec::new();
        }
    });
}

/// Frees the buffers of this thread and of every thread of the rayon pool (the solves
/// and the row blocks of the dense products run there and keep up to `KEEP_ENTRIES`
/// values each), and the row-major buffers of the sparse products.
pub(crate) fn release_all() {
    let both = || {
        release();
        release_rows();
    };
    both();
    rayon::broadcast(|_| both());
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn release_all_frees_the_buffers_of_the_pool_threads() {
        // Every pool thread keeps a buffer with a capacity no other buffer has: `take`
        // hands out the smallest kept buffer that is large enough, and a fresh buffer
        // has exactly the capacity asked for...
        // ...on a pool of its own: the tests run side by side, and another test's solve
        // on the global pool calls `release_all` there.
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .expect("a thread pool");
        pool.install(|| {
            const ODD: usize = 12_345;
            let marked = |b: &Vec<f64>| b.capacity() == ODD + 7;
            rayon::broadcast(|_| {
                let mut b = Vec::with_capacity(ODD + 7);
                b.resize(ODD, 1.0);
                give(b)
            });
            assert!(
                rayon::broadcast(|_| {
                    let b = take(ODD);
                    let kept = marked(&b);
                    give(b);
                    kept
                })
                .iter()
                .all(|&kept| kept)
            );
            // ...until release_all.
            release_all();
            assert!(
                rayon::broadcast(|_| !marked(&take(ODD)))
                    .iter()
                    .all(|&fresh| fresh)
            );
        });
    }

    /// Another solve's `release_all` can reach a thread inside a sparse product, which
    /// holds the row buffer across a parallel loop: the buffer is then left alone, not a
    /// panic.
    #[test]
    fn releasing_a_busy_row_buffer_is_skipped() {
        ROWS.with(|cell| {
            let mut busy = cell.borrow_mut();
            busy.resize(10, 1.0);
            release_rows();
            assert_eq!(busy.len(), 10);
        });
        release_rows();
        ROWS.with(|cell| assert_eq!(cell.borrow().capacity(), 0));
    }

    #[test]
    fn releasing_a_busy_pool_is_skipped() {
        give(vec![0.0; 77]);
        POOL.with(|p| {
            let busy = p.borrow_mut();
            let kept = busy.len();
            assert!(kept > 0);
            // No panic on the borrow held here, and nothing is taken from under it.
            release();
            assert_eq!(busy.len(), kept);
        });
        release();
        POOL.with(|p| assert!(p.borrow().is_empty()));
    }

    #[test]
    fn buffers_are_zeroed_and_reused() {
        let mut a = take(1000);
        assert!(a.iter().all(|&x| x == 0.0));
        a.iter_mut().for_each(|x| *x = 7.0);
        let ptr = a.as_ptr();
        give(a);
        let b = take(500);
        assert_eq!(b.len(), 500);
        assert!(b.iter().all(|&x| x == 0.0));
        assert_eq!(b.as_ptr(), ptr, "the returned buffer is reused");
        give(b);
        release();
        let c = take(10);
        assert_ne!(
            c.capacity(),
            1000,
            "released buffers are not handed out again"
        );
    }
}
