//! A writer of Nastran OP2 files of real modes for tests and benchmarks, written from the
//! layout MSC Nastran's OP2 files have (`fixtures/nastran/pynastran/mode_solid_shell_bar.op2`;
//! the tables' markers as pyNastran documents them) and sharing no code with femu's reader: the
//! file header, a `GEOM1` table with no data, and `OUGV1` with one identification record (146
//! words: approach code 2, table code 7, the subcase, the mode and its eigenvalue, format 1, 8
//! words a point) and one data record (`10 id + 3`, point type 1, `T1 T2 T3 R1 R2 R3`) per mode.

/// The bytes of an OP2 holding `modes` (eigenvalue and, per grid of `grids`, six components).
pub fn op2_modes(grids: &[u64], modes: &[(f32, Vec<[f32; 6]>)], little: bool) -> Vec<u8> {
    let word = |v: i32| {
        if little {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        }
    };
    let float = |v: f32| {
        if little {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        }
    };
    let mut b = Vec::new();
    let mut record = |data: &[u8]| {
        b.extend(word(data.len() as i32));
        b.extend_from_slice(data);
        b.extend(word(data.len() as i32));
    };
    let int = |v: i32| word(v).to_vec();
    record(&int(3));
    record(&[0; 12]);
    record(&int(7));
    record(b"NASTRAN FORT TAPE ID CODE - ");
    record(&int(2));
    record(b"XXXXXXXX");
    record(&int(-1));
    record(&int(0));
    for name in [b"GEOM1   ", b"OUGV1   "] {
        record(&int(2));
        record(name);
        record(&int(-1));
        record(&int(7));
        record(&[0; 28]);
        record(&int(-2));
        record(&int(1));
        record(&int(0));
        record(&int(2));
        record(name);
        let mut marker = -3;
        if name == b"OUGV1   " {
            for (j, (eigenvalue, shape)) in modes.iter().enumerate() {
                let mut ident = Vec::with_capacity(584);
                for v in [22, 7, 0, 1, j as i32 + 1] {
                    ident.extend(word(v));
                }
                ident.extend(float(*eigenvalue));
                ident.extend(word(0));
                ident.extend(word(0));
                ident.extend(word(1));
                ident.extend(word(8));
                ident.resize(584, 0);
                let mut points = Vec::with_capacity(32 * grids.len());
                for (g, v) in grids.iter().zip(shape) {
                    points.extend(word(10 * *g as i32 + 3));
                    points.extend(word(1));
                    for x in v {
                        points.extend(float(*x));
                    }
                }
                for rec in [&ident, &points] {
                    record(&int(marker));
                    record(&int(1));
                    record(&int(0));
                    record(&int((rec.len() / 4) as i32));
                    record(rec);
                    marker -= 1;
                }
            }
        }
        record(&int(marker));
        record(&int(1));
        record(&int(0));
        record(&int(0));
    }
    record(&int(0));
    b
}
