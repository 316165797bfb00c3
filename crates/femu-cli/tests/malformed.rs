//! The corpus of malformed and misspelt inputs under `fixtures/malformed/`: every file gives an
//! error (exit status 1 or 2, nothing on stdout, no output file), and the exact text the user
//! sees, warnings included, is a reviewed snapshot.
//!
//! `model/`: read by `femu modes FILE --count 2` (meshes with a material on the command line);
//! `test/`: read by `femu correlate ../../inp/two_hex.inp FILE`; `study/`: run by
//! `femu run FILE --out OUT`. Each runs in its folder, so the messages hold bare file names.

use assert_cmd::Command;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

fn corpus(kind: &str) -> (PathBuf, Vec<String>) {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/malformed")
        .join(kind);
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    (dir, names)
}

/// Runs `args` in `dir`; returns the snapshot entry and checks the failure contract.
fn run(dir: &Path, name: &str, args: &[&str], out: &mut String) {
    let output = Command::cargo_bin("femu")
        .unwrap()
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap();
    let code = output.status.code().unwrap_or(-1);
    assert!(
        code == 1 || code == 2,
        "{name}: exit status {code}, stdout {}",
        String::from_utf8_lossy(&output.stdout)
    );
    assert!(
        output.stdout.is_empty(),
        "{name}: a result on stdout: {}",
        String::from_utf8_lossy(&output.stdout)
    );
    let stderr = String::from_utf8_lossy(&output.stderr);
    // the good model's own warnings are the same for every test file: keep the snapshot short
    let text: Vec<&str> = stderr
        .lines()
        .filter(|l| !l.starts_with("warning: ../../inp/two_hex.inp"))
        .collect();
    let _ = writeln!(out, "== {name} (exit {code})\n{}", text.join("\n"));
}

#[test]
fn model_files() {
    let (dir, names) = corpus("model");
    let mut out = String::new();
    for name in &names {
        let mut args = vec!["modes", name.as_str(), "--count", "2"];
        if !name.ends_with(".inp") {
            args.extend(["--young", "2.1e11", "--poisson", "0.3", "--density", "7850"]);
        }
        run(&dir, name, &args, &mut out);
    }
    assert!(names.len() >= 35, "{} model cases", names.len());
    insta::assert_snapshot!(out);
}

#[test]
fn test_files() {
    let (dir, names) = corpus("test");
    let mut out = String::new();
    for name in &names {
        run(
            &dir,
            name,
            &["correlate", "../../inp/two_hex.inp", name.as_str()],
            &mut out,
        );
    }
    insta::assert_snapshot!(out);
}

#[test]
fn study_files() {
    let (dir, names) = corpus("study");
    let out_dir = std::env::temp_dir().join(format!("femu-malformed-{}", std::process::id()));
    let mut out = String::new();
    for name in &names {
        let target = out_dir.join(name);
        run(
            &dir,
            name,
            &["run", name.as_str(), "--out", target.to_str().unwrap()],
            &mut out,
        );
        // nothing is written for a study that fails before its first result
        assert!(
            !target.join("report.json").exists(),
            "{name}: a report was written"
        );
    }
    insta::assert_snapshot!(out);
}

/// The same misspellings read with `--lenient`: an unknown keyword becomes a warning (and the
/// deck is read without it), an unknown parameter stays an error.
#[test]
fn lenient_reads_unknown_keywords_only() {
    let (dir, _) = corpus("model");
    let ok = Command::cargo_bin("femu")
        .unwrap()
        .current_dir(&dir)
        .args(["modes", "typo_boundary.inp", "--count", "2", "--lenient"])
        .output()
        .unwrap();
    assert!(ok.status.success());
    let stderr = String::from_utf8_lossy(&ok.stderr);
    assert!(
        stderr.contains("typo_boundary.inp:37: unknown keyword *BOUNDRY (did you mean *BOUNDARY?) skipped (--lenient)"),
        "{stderr}"
    );
    // free-free without its clamp: six rigid-body modes at the bottom, completed as a cluster
    let stdout = String::from_utf8_lossy(&ok.stdout);
    assert!(stdout.contains("| backward |"), "{stdout}");
    let err = Command::cargo_bin("femu")
        .unwrap()
        .current_dir(&dir)
        .args(["modes", "typo_generate.inp", "--lenient"])
        .output()
        .unwrap();
    assert_eq!(err.status.code(), Some(1));
    // with --lenient the misspelt keyword is skipped and the error it causes names its own line,
    // after the warning that explains it
    let err = Command::cargo_bin("femu")
        .unwrap()
        .current_dir(&dir)
        .args(["modes", "typo_element.inp", "--lenient"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&err.stderr);
    let warning = stderr.find("unknown keyword *ELEMNT").expect("the warning");
    let error = stderr
        .find("error: typo_element.inp:29:")
        .expect("the error");
    assert!(warning < error, "{stderr}");
}

/// `femu info` on one file of each format (run in `fixtures/` so that the paths are short): what
/// each holds and what femu would do with it, as a reviewed snapshot.
#[test]
fn info_describes_every_format() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures");
    let mut out = String::new();
    for f in [
        "inp/two_hex.inp",
        "msh/mixed_v22.msh",
        "msh/box_mixed1.unv",
        "uff/plate_test.unv",
        "uff/pyuff/testlab_161_164_18_15_82.uff",
        "csv/two_modes.csv",
        "frd/cantilever.frd",
        "calculix/cantilever.sti",
        "nastran/pynastran/mode_solid_shell_bar.f06",
        "nastran/pynastran/mode_solid_shell_bar.op2",
        "nastran/pynastran/beam_modes.dat",
    ] {
        let o = Command::cargo_bin("femu")
            .unwrap()
            .current_dir(&dir)
            .args(["info", f])
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{f}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        out.push_str(&String::from_utf8_lossy(&o.stdout));
        out.push('\n');
    }
    insta::assert_snapshot!(out);
}
