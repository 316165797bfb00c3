//! Reading another solver's binary matrices and modes against reading their bytes
//! (docs/SCALING.md, "Reading another solver's matrices"): a stiffness-like pair on `FEMU_BENCH_OP4_DOF` rows
//! (default 1,000,000: three DOFs a node on a cube of nodes, each row coupled to the 27 nodes
//! around its own, 81 entries an interior row, as a hex8 model's `K` and `M` are) written as a
//! binary OUTPUT4 file (`KGG`, `MGG`, sparse `BIGMAT` columns, double precision, by
//! `femu_testkit::op4`), then, in a fresh process so that its peak memory is the reader's alone:
//! the file's bytes read into memory from a warm cache, `femu::io::op4::read_op4` (medians of
//! `FEMU_BENCH_REPS`, default 3), the ratio, and the process's peak resident memory against the
//! matrices it holds (`16 bytes` an entry and `8` a column pointer). Then the same for an OP2 of
//! 50 real modes on a sixth of the rows' count of grids (six components each, `femu_testkit::op2`)
//! read by `femu_io::op2::read_op2`, against the modes it holds.
//!
//! Run: `cargo bench --bench external_read` (`FEMU_BENCH_OP4_KEEP=FILE` keeps the file;
//! `FEMU_BENCH_OP4_TEXT=1` times the pair as OUTPUT4 text too).

use femu_testkit::op4::{Op4Layout, Op4Out, op4_binary};
use std::time::Instant;

fn median(mut t: Vec<f64>) -> f64 {
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

/// Writes `bytes` and waits until they are on disk: the reads timed next are not slowed by the
/// system writing them back.
fn write_synced(path: &std::path::Path, bytes: &[u8]) {
    use std::io::Write;
    let mut f = std::fs::File::create(path).unwrap();
    f.write_all(bytes).unwrap();
    f.sync_all().unwrap();
}

/// The process's peak resident memory, bytes (`VmHWM`).
fn peak_rss() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<u64>().ok())
        })
        .map_or(0, |kb| kb * 1024)
}

/// The columns of the pair on a cube of `n^3` nodes, 3 DOFs each.
fn columns(n: usize, mass: bool) -> Vec<Vec<(usize, f64)>> {
    let node = |i: usize, j: usize, k: usize| i + n * (j + n * k);
    let mut cols = Vec::with_capacity(3 * n * n * n);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                for a in 0..3 {
                    let c = 3 * node(i, j, k) + a;
                    let mut col = Vec::with_capacity(81);
                    for kk in k.saturating_sub(1)..(k + 2).min(n) {
                        for jj in j.saturating_sub(1)..(j + 2).min(n) {
                            for ii in i.saturating_sub(1)..(i + 2).min(n) {
                                for b in 0..3 {
                                    let r = 3 * node(ii, jj, kk) + b;
                                    // symmetric values: a function of the unordered pair
                                    let (lo, hi) = (r.min(c), r.max(c));
                                    let v = if r == c {
                                        if mass { 2.0 } else { 26.0 }
                                    } else {
                                        -(((lo * 31 + hi * 17) % 97) as f64 + 1.0) / 97.0
                                            * if mass { -0.01 } else { 1.0 }
                                    };
                                    col.push((r, v));
                                }
                            }
                        }
                    }
                    col.sort_by_key(|e| e.0);
                    cols.push(col);
                }
            }
        }
    }
    cols
}

/// Times reading `path`'s bytes from a warm cache against `read` (which returns the bytes it
/// holds), medians of `reps`, and prints the ratio and the peak resident memory.
fn measure(label: &str, path: &str, reps: usize, read: impl Fn(&std::path::Path) -> u64) {
    let path = std::path::PathBuf::from(path);
    let _ = std::fs::read(&path).unwrap(); // warm the cache
    let bytes: Vec<f64> = (0..reps)
        .map(|_| {
            let t = Instant::now();
            let b = std::fs::read(&path).unwrap();
            std::hint::black_box(&b);
            t.elapsed().as_secs_f64()
        })
        .collect();
    let before = peak_rss();
    let mut held = 0u64;
    let reads: Vec<f64> = (0..reps)
        .map(|_| {
            let t = Instant::now();
            held = read(&path);
            t.elapsed().as_secs_f64()
        })
        .collect();
    let (b, r) = (median(bytes), median(reads));
    println!(
        "{label}: bytes read {b:.3} s, reader {r:.3} s ({:.2}x); held {:.0} MB, peak resident {:.0} MB before the reader and {:.0} MB after ({:.2}x what it holds)",
        r / b,
        held as f64 / 1e6,
        before as f64 / 1e6,
        peak_rss() as f64 / 1e6,
        peak_rss() as f64 / held as f64
    );
}

fn main() {
    let reps: usize = std::env::var("FEMU_BENCH_REPS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(3);
    // the fresh process: the bytes, then the reader
    if let Ok(path) = std::env::var("FEMU_BENCH_OP2_READ") {
        measure("OP2: read_op2", &path, reps, |p| {
            let f = femu::io::op2::read_op2(p).unwrap();
            f.modes
                .iter()
                .map(|m| std::mem::size_of_val(m.points.as_slice()) as u64)
                .sum()
        });
        return;
    }
    if let Ok(path) = std::env::var("FEMU_BENCH_OP4_READ") {
        measure("read_op4", &path, reps, |p| {
            let m = femu::io::op4::read_op4(p).unwrap();
            m.iter()
                .map(|a| 16 * a.re.len() as u64 + 8 * a.col_start.len() as u64)
                .sum()
        });
        return;
    }
    let dof: usize = std::env::var("FEMU_BENCH_OP4_DOF")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1_000_000);
    let n = ((dof as f64 / 3.0).cbrt().round() as usize).max(2);
    let rows = 3 * n * n * n;
    let dir = std::env::temp_dir().join(format!("femu_bench_op4_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // FEMU_BENCH_OP4_KEEP=FILE: the file is written there and kept (to profile the reader alone)
    let kept = std::env::var("FEMU_BENCH_OP4_KEEP").ok();
    let path = kept
        .as_ref()
        .map_or_else(|| dir.join("job.op4"), std::path::PathBuf::from);
    {
        let t = Instant::now();
        let k = Op4Out {
            name: "KGG",
            rows,
            form: 6,
            columns: columns(n, false),
        };
        let mut bytes = op4_binary(std::slice::from_ref(&k), Op4Layout::BigMat, true);
        drop(k);
        let m = Op4Out {
            name: "MGG",
            rows,
            form: 6,
            columns: columns(n, true),
        };
        bytes.extend(op4_binary(
            std::slice::from_ref(&m),
            Op4Layout::BigMat,
            true,
        ));
        drop(m);
        write_synced(&path, &bytes);
        println!(
            "{rows} rows ({n}^3 nodes), {:.0} MB written in {:.1} s",
            bytes.len() as f64 / 1e6,
            t.elapsed().as_secs_f64()
        );
    }
    let status = std::process::Command::new(std::env::current_exe().unwrap())
        .env("FEMU_BENCH_OP4_READ", &path)
        .status()
        .unwrap();
    assert!(status.success());
    // FEMU_BENCH_OP4_TEXT=1: the same pair as OUTPUT4 text (1P,3E23.16), read the same way
    if std::env::var("FEMU_BENCH_OP4_TEXT").is_ok() {
        let text = dir.join("job_text.op4");
        let pair = [
            Op4Out {
                name: "KGG",
                rows,
                form: 6,
                columns: columns(n, false),
            },
            Op4Out {
                name: "MGG",
                rows,
                form: 6,
                columns: columns(n, true),
            },
        ];
        let s = femu_testkit::op4::op4_text(&pair, Op4Layout::BigMat);
        write_synced(&text, s.as_bytes());
        println!("text: {:.0} MB", s.len() as f64 / 1e6);
        drop(s);
        let status = std::process::Command::new(std::env::current_exe().unwrap())
            .env("FEMU_BENCH_OP4_READ", &text)
            .status()
            .unwrap();
        assert!(status.success());
    }
    // an OP2 of 50 modes on a third of the rows' grids (six components each)
    let op2 = dir.join("modes.op2");
    {
        let grids: Vec<u64> = (1..=(rows as u64).div_ceil(6)).collect();
        let modes: Vec<(f32, Vec<[f32; 6]>)> = (0..50)
            .map(|j| {
                let shape = grids
                    .iter()
                    .map(|&g| {
                        std::array::from_fn(|c| ((g as f32) * 0.001 + c as f32 + j as f32).sin())
                    })
                    .collect();
                (1e3 * (j + 1) as f32, shape)
            })
            .collect();
        let bytes = femu_testkit::op2::op2_modes(&grids, &modes, true);
        write_synced(&op2, &bytes);
        println!(
            "OP2: {} grids x 50 modes, {:.0} MB",
            grids.len(),
            bytes.len() as f64 / 1e6
        );
    }
    let status = std::process::Command::new(std::env::current_exe().unwrap())
        .env("FEMU_BENCH_OP2_READ", &op2)
        .status()
        .unwrap();
    assert!(status.success());
    let _ = std::fs::remove_dir_all(&dir);
}
