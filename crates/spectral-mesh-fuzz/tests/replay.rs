//! Every committed fuzz input fed again to its target's check, as an ordinary test: the
//! seeds (`fuzz/seeds/TARGET/*`, what each fuzz run starts from) and the regressions
//! (`fuzz/regressions/TARGET/*`: every input a fuzzer found, crash, hang, out-of-memory
//! or broken promise, and a few made by hand for the same bugs; `RELIABILITY.md` lists
//! what each found and the commit that fixed it).
//!
//! Each input runs on a thread with a 256 KiB stack (a server's worker threads have
//! 2 MiB; the web target, which drives an async runtime, gets those 2 MiB) and must finish
//! within 20 s. One test per target, so they run side by side.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, Instant};

const STACK: usize = 256 * 1024;
const WEB_STACK: usize = 2 * 1024 * 1024;
const TIME_LIMIT: Duration = Duration::from_secs(20);

fn fuzz_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz")
}

/// The committed inputs of `target`: its seeds and its regressions, sorted.
fn inputs(target: &str) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for corpus in ["seeds", "regressions"] {
        let dir = fuzz_dir().join(corpus).join(target);
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for e in entries {
            let p = e.unwrap().path();
            if p.is_file() {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

fn replay(target: &str) {
    let run = spectral_mesh_fuzz::targets::ALL
        .iter()
        .find(|(name, _)| *name == target)
        .map(|&(_, run)| run)
        .unwrap_or_else(|| panic!("no target {target}"));
    let all = inputs(target);
    assert!(!all.is_empty(), "{target}: no seeds in {:?}", fuzz_dir());
    let stack = if target == "web_body" {
        WEB_STACK
    } else {
        STACK
    };
    for path in all {
        let bytes = std::fs::read(&path).unwrap();
        let label = format!("{target}: {}", path.display());
        let (tx, rx) = mpsc::channel();
        let t0 = Instant::now();
        let worker = std::thread::Builder::new()
            .name(label.clone())
            .stack_size(stack)
            .spawn(move || {
                run(&bytes);
                tx.send(()).unwrap();
            })
            .unwrap();
        match rx.recv_timeout(TIME_LIMIT) {
            Ok(()) => worker.join().unwrap(),
            Err(mpsc::RecvTimeoutError::Timeout) => {
                panic!("{label}: still running after {TIME_LIMIT:?}")
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                eprintln!("{label}: failed");
                if let Err(p) = worker.join() {
                    std::panic::resume_unwind(p);
                }
            }
        }
        let took = t0.elapsed();
        if took > Duration::from_secs(2) {
            eprintln!("{label}: slow, {took:?}");
        }
    }
}

macro_rules! replay_tests {
    ($($name:ident),* $(,)?) => {
        $(
            #[test]
            fn $name() {
                replay(stringify!($name));
            }
        )*

        /// Every target of the crate has its test here (a new target without one fails).
        #[test]
        fn every_target_is_replayed() {
            let tested = [$(stringify!($name)),*];
            for (name, _) in spectral_mesh_fuzz::targets::ALL {
                assert!(tested.contains(name), "target {name} has no replay test");
            }
        }
    };
}

replay_tests!(
    basis_npz,
    constraints,
    detect_format,
    experiment_file,
    field_request,
    field_text,
    filter,
    filter_expr,
    perturb_spec,
    pipeline_eigen,
    pipeline_points,
    read_obj,
    read_off,
    read_ply_ascii,
    read_ply_binary,
    read_points,
    read_stl_ascii,
    read_stl_binary,
    shape,
    validate_repair,
    web_body,
);

/// The size checks of the archive reader do not refuse what NumPy writes
/// (`numpy.savez_compressed`, Fortran-ordered eigenvectors, numpy 2.4).
#[test]
fn an_archive_written_by_numpy_still_loads() {
    let path = fuzz_dir().join("regressions/basis_npz/numpy-savez-compressed");
    let bytes = std::fs::read(path).unwrap();
    let (b, meta) = spectral_mesh::spectral::store::load_npz_from_reader(
        std::io::Cursor::new(&bytes[1..]),
        "np",
    )
    .unwrap();
    assert_eq!((b.n, b.k()), (5, 3));
    assert_eq!(meta.generator, "numpy.savez");
    assert_eq!(b.values, vec![0.0, 1.25, 2.5]);
    // Entry (i, j) of the (5, 3) array is (3 i + j) / 10; column-major in memory.
    assert_eq!(b.vectors[2 * 5 + 4], 1.4);
    assert_eq!(b.residuals, vec![1e-13; 3]);
}
