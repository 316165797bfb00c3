//! The model of the eigensolver comparison (`benches/peers/run.sh`): a steel block 2 x 1 x 1 m,
//! clamped at x = 0, meshed with hex8, hex20 or tet10 (`n` cells across, `2n` along).
//!
//! - `peer_modes export KIND N COUNT DIR`: writes `DIR/model.inp` (CalculiX, `*FREQUENCY` step
//!   with COUNT modes) and `DIR/K.mtx`, `DIR/M.mtx` (scipy).
//! - `peer_modes solve KIND N COUNT`: assembles and solves with femu, prints one JSON line with
//!   the frequencies, the Sturm check and where the time went.

use femu::prelude::*;
use femu::sparse::eigen::{EigenParams, Which, eigs};
use std::fmt::Write as _;
use std::time::Instant;

fn model(kind: &str, n: usize) -> Result<Model, Box<dyn std::error::Error>> {
    let (cells, quadratic) = match kind {
        "hex8" => (BoxCells::Hex, false),
        "hex20" => (BoxCells::Hex, true),
        "tet10" => (BoxCells::Tet6, true),
        other => return Err(format!("unknown kind {other} (hex8, hex20, tet10)").into()),
    };
    let mut model = Model::new(box_mesh(&BoxSpec::new(
        [2.0, 1.0, 1.0],
        [2 * n, n, n],
        cells,
        quadratic,
    ))?)?;
    model.set_material(None, Material::steel())?;
    model.fix_set("xmin", &[0, 1, 2])?;
    Ok(model)
}

/// A minimal CalculiX deck for the benchmark (the full `.inp` writer is femu-io's).
fn write_inp(model: &Model, count: usize, path: &std::path::Path) -> std::io::Result<()> {
    let mesh = model.mesh();
    let mut s = String::from("*HEADING\nfemu eigensolver benchmark\n*NODE, NSET=NALL\n");
    for i in 0..mesh.node_count() {
        let x = mesh.coords()[i];
        // shortest round-trip form: CalculiX rejects fields over 20 characters
        let _ = writeln!(s, "{}, {}, {}, {}", mesh.node_id(i), x[0], x[1], x[2]);
    }
    let kind = mesh.element(0).kind;
    let _ = writeln!(s, "*ELEMENT, TYPE={}, ELSET=EALL", kind.abaqus_name());
    for el in mesh.elements() {
        let ids: Vec<String> = std::iter::once(el.id)
            .chain(el.nodes.iter().map(|n| mesh.node_id(*n)))
            .map(|v| v.to_string())
            .collect();
        // at most 16 entries per line; a trailing comma continues the line
        for (c, chunk) in ids.chunks(16).enumerate() {
            let last = (c + 1) * 16 >= ids.len();
            let _ = writeln!(s, "{}{}", chunk.join(", "), if last { "" } else { "," });
        }
    }
    s.push_str("*NSET, NSET=FIX\n");
    for chunk in mesh.node_set("xmin").expect("generated set").chunks(16) {
        let ids: Vec<String> = chunk.iter().map(|n| mesh.node_id(*n).to_string()).collect();
        let _ = writeln!(s, "{}", ids.join(", "));
    }
    let _ = write!(
        s,
        "*BOUNDARY\nFIX, 1, 3\n*MATERIAL, NAME=STEEL\n*ELASTIC\n210e9, 0.3\n*DENSITY\n7850.\n*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL\n*STEP\n*FREQUENCY\n{count}\n*END STEP\n"
    );
    std::fs::write(path, s)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: peer_modes (export KIND N COUNT DIR | solve KIND N COUNT)";
    if args.len() < 5 {
        return Err(usage.into());
    }
    let (kind, n, count): (&str, usize, usize) = (&args[2], args[3].parse()?, args[4].parse()?);
    let t = Instant::now();
    let model = model(kind, n)?;
    let sys = model.assemble(MassKind::Consistent)?;
    let t_assembly = t.elapsed().as_secs_f64();
    match args[1].as_str() {
        "export" => {
            let dir = std::path::Path::new(args.get(5).ok_or(usage)?);
            std::fs::create_dir_all(dir)?;
            write_inp(&model, count, &dir.join("model.inp"))?;
            femu::sparse::mtx::write_matrix_market(dir.join("K.mtx"), &sys.k, true)?;
            femu::sparse::mtx::write_matrix_market(dir.join("M.mtx"), &sys.m, true)?;
            println!(
                "{{\"dofs\": {}, \"elements\": {}}}",
                sys.dofs.free_count(),
                model.mesh().element_count()
            );
        }
        "solve" => {
            let t = Instant::now();
            let mut params = EigenParams::default();
            if let Some(b) = std::env::var("FEMU_BLOCK")
                .ok()
                .and_then(|v| v.parse().ok())
            {
                params.block_size = b; // for tuning runs
            }
            if let Some(m) = std::env::var("FEMU_MAX_BASIS")
                .ok()
                .and_then(|v| v.parse().ok())
            {
                params.max_basis = m; // for tuning runs
            }
            let modes = eigs(&sys.k, &sys.m, Which::Lowest(count), &params)?;
            let t_eigen = t.elapsed().as_secs_f64();
            let s = &modes.stats;
            let f: Vec<String> = modes
                .frequencies_hz()
                .iter()
                .take(count)
                .map(|v| format!("{v:.10e}"))
                .collect();
            let worst = modes
                .residuals
                .iter()
                .take(count)
                .fold(0.0_f64, |m, r| m.max(*r));
            println!(
                "{{\"dofs\": {}, \"assembly_s\": {t_assembly:.3}, \"eigen_s\": {t_eigen:.3}, \"symbolic_s\": {:.3}, \"factor_s\": {:.3}, \"solve_s\": {:.3}, \"orth_s\": {:.3}, \"factorizations\": {}, \"solved_vectors\": {}, \"restarts\": {}, \"factor_len\": {}, \"sturm_verified\": {}, \"max_residual\": {worst:.2e}, \"frequencies_hz\": [{}]}}",
                sys.dofs.free_count(),
                s.symbolic_seconds,
                s.factor_seconds,
                s.solve_seconds,
                s.orthogonalization_seconds,
                s.factorizations,
                s.solved_vectors,
                s.restarts,
                s.factor_len,
                modes.sturm.verified(),
                f.join(", ")
            );
        }
        _ => return Err(usage.into()),
    }
    Ok(())
}
