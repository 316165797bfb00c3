//! Writes a clamped steel block as a CalculiX deck with a `*FREQUENCY` step, through femu-io:
//! `cargo run --release --example export_inp KIND NX NY NZ COUNT OUT.inp` (KIND: hex8, hex20,
//! tet10, penta6, penta15, tet4). Used to compare `femu modes` with CalculiX on the same deck.

use femu::io::inp::{FrequencyStep, write_inp};
use femu::prelude::*;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().collect();
    if a.len() != 7 {
        return Err("usage: export_inp KIND NX NY NZ COUNT OUT.inp".into());
    }
    let (cells, quadratic) = match a[1].as_str() {
        "hex8" => (BoxCells::Hex, false),
        "hex20" => (BoxCells::Hex, true),
        "tet4" => (BoxCells::Tet6, false),
        "tet10" => (BoxCells::Tet6, true),
        "penta6" => (BoxCells::Wedge, false),
        "penta15" => (BoxCells::Wedge, true),
        k => return Err(format!("unknown kind {k}").into()),
    };
    let n: Vec<usize> = a[2..5]
        .iter()
        .map(|s| s.parse())
        .collect::<Result<_, _>>()?;
    let spec = BoxSpec::new([0.4, 0.1, 0.05], [n[0], n[1], n[2]], cells, quadratic);
    let mut model = Model::new(box_mesh(&spec)?)?;
    model.set_material(None, Material::steel())?;
    model.fix_set("xmin", &[0, 1, 2])?;
    let step = FrequencyStep {
        count: a[5].parse()?,
        shift_cycles2: None,
    };
    write_inp(&model, Some(&step), &a[6])?;
    Ok(())
}
