//! The paper's plate study through the facade: `cargo run --release --example demo [OUT_DIR]`
//! (the same study as `femu demo`). Writes the report (Markdown, SVG, JSON, VTK, UFF) and prints
//! where it is.

use femu::study::demo::{DemoOptions, run_demo};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "femu-demo".into());
    let mut opts = DemoOptions {
        out: out.into(),
        ..Default::default()
    };
    // optional: shape noise and frequency noise (fractions)
    if let Some(v) = std::env::args().nth(2) {
        opts.shape_noise = v.parse()?;
    }
    if let Some(v) = std::env::args().nth(3) {
        opts.frequency_noise = v.parse()?;
    }
    let t = std::time::Instant::now();
    let report = run_demo(&opts, |line| println!("{line}"))?;
    println!("\n{}", std::fs::read_to_string(opts.out.join("report.md"))?);
    println!(
        "report written to {} in {:.1} s:",
        opts.out.display(),
        t.elapsed().as_secs_f64()
    );
    for f in &report.files {
        println!("  {}", f.display());
    }
    Ok(())
}
