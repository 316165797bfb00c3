//! CalculiX (`ccx`) for the tests that compare femu with it: whether it is installed (required
//! when `FEMU_REQUIRE_CCX` is set, as `.ci/run` sets it), running a job, and the eigenvalues of
//! its `.dat` file.

use std::path::Path;
use std::process::Command;

/// Whether `ccx` is on the path. Panics when it is not and `FEMU_REQUIRE_CCX` is set (CI), so
/// that a missing CalculiX fails there instead of skipping; elsewhere says the test was skipped.
pub fn available() -> bool {
    let found = Command::new("ccx").arg("-v").output().is_ok();
    if !found && std::env::var_os("FEMU_REQUIRE_CCX").is_some() {
        panic!("FEMU_REQUIRE_CCX is set but ccx is not on PATH");
    }
    if !found {
        eprintln!("skipped: ccx (CalculiX) is not installed");
    }
    found
}

/// Runs `ccx -i job` in `dir` (which holds `job.inp`); panics with CalculiX's output if it fails.
pub fn run(dir: &Path, job: &str) {
    let out = Command::new("ccx")
        .arg("-i")
        .arg(job)
        .current_dir(dir)
        .output()
        .expect("ccx runs");
    assert!(
        out.status.success(),
        "ccx failed: {}",
        String::from_utf8_lossy(&out.stdout)
    );
}

/// The eigenvalues of a `.dat` file's "E I G E N V A L U E   O U T P U T" table (7 digits).
pub fn eigenvalues(dat: &str) -> Vec<f64> {
    let start = dat
        .find("E I G E N V A L U E   O U T P U T")
        .expect("eigenvalue table in the .dat file");
    dat[start..]
        .lines()
        .skip(1)
        .map(str::trim)
        .skip_while(|l| !l.starts_with(|c: char| c.is_ascii_digit()))
        .take_while(|l| l.starts_with(|c: char| c.is_ascii_digit()))
        .map(|l| l.split_whitespace().nth(1).unwrap().parse::<f64>().unwrap())
        .collect()
}

/// The eigenvalues CalculiX prints for `deck` (its `*FREQUENCY` step), run in a fresh folder of
/// the temporary directory named by `tag` (removed afterwards).
pub fn frequency_eigenvalues(deck: &str, tag: &str) -> Vec<f64> {
    let dir = std::env::temp_dir().join(format!("femu-ccx-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary folder");
    std::fs::write(dir.join("job.inp"), deck).expect("the deck written");
    run(&dir, "job");
    let dat = std::fs::read_to_string(dir.join("job.dat")).expect("CalculiX's job.dat");
    let _ = std::fs::remove_dir_all(&dir);
    eigenvalues(&dat)
}
