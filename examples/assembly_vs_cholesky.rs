//! Times the assembly of K and M of a clamped hex8 cube against one sparse Cholesky
//! factorization of its K (femu-sparse: ordering + symbolic analysis, then numeric LL^T), and
//! prints the ratio.
//!
//! `cargo run --release --example assembly_vs_cholesky -- [CELLS_PER_SIDE] [nd|amd|assembly-only]`
//! (default 40 cells: 201,720 DOF, nested dissection); `assembly-only` skips the factorization.

use femu::prelude::*;
use femu::sparse::cholesky::SymbolicFactor;
use femu::sparse::ordering::Ordering;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let n: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(40);
    let ordering = match std::env::args().nth(2).as_deref() {
        Some("amd") => Ordering::Amd,
        _ => Ordering::NestedDissection,
    };
    // "assembly-only": for sizes whose factor does not fit in memory (1M DOF needs ~20 GB)
    let factor = std::env::args().nth(2).as_deref() != Some("assembly-only");
    let mut model = Model::new(box_mesh(&BoxSpec::new(
        [1.0; 3],
        [n; 3],
        BoxCells::Hex,
        false,
    ))?)?;
    model.set_material(None, Material::steel())?;
    model.fix_set("xmin", &[0, 1, 2])?;
    let t = Instant::now();
    let asm = Assembler::new(&model)?;
    let t_pattern = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let sys = asm.assemble(&model, MassKind::Consistent)?;
    let t_assembly = t.elapsed().as_secs_f64();
    println!(
        "hex8 {n}^3: {} elements, {} DOF, nnz(K) = {}",
        model.mesh().element_count(),
        sys.dofs.free_count(),
        sys.k.nnz()
    );
    println!("pattern + colouring   {t_pattern:8.3} s");
    println!("assembly of K and M   {t_assembly:8.3} s");
    if !factor {
        return Ok(());
    }
    let t = Instant::now();
    let symbolic = SymbolicFactor::new(&sys.k, ordering)?;
    let t_symbolic = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let _llt = symbolic.llt(&sys.k, "K")?;
    let t_numeric = t.elapsed().as_secs_f64();
    println!("pattern + colouring   {t_pattern:8.3} s");
    println!("assembly of K and M   {t_assembly:8.3} s");
    println!(
        "Cholesky symbolic     {t_symbolic:8.3} s ({ordering:?}, {} values in L)",
        symbolic.factor_len()
    );
    println!("Cholesky numeric      {t_numeric:8.3} s");
    println!(
        "assembly / Cholesky = {:.4} (pattern included: {:.4})",
        t_assembly / (t_symbolic + t_numeric),
        (t_pattern + t_assembly) / (t_symbolic + t_numeric)
    );
    Ok(())
}
