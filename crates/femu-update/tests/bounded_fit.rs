//! The explained residual within the parameters' bounds: a factor the data would take past its
//! bound is held there, and the fraction reported is what the bounded factors remove (the reach
//! said "k:EALL -0.900 removes 93 % of the expanded residual" from the unbounded fit while the
//! residual at -0.9 was ten times larger). Against the box-constrained minimum of
//! `f(theta) = r^T W r + 2 b . theta + theta^T G theta` worked out by hand from its KKT conditions.

use femu_update::{Localisation, SelectionRule};

fn localisation(
    gram: Vec<Vec<f64>>,
    num: Vec<f64>,
    objective: f64,
    bounds: Vec<(f64, f64)>,
) -> Localisation {
    Localisation {
        ranking: Vec::new(),
        selected: Vec::new(),
        rule: SelectionRule::default(),
        normal: Some((gram, num, objective)),
        bounds,
    }
}

#[test]
fn one_group_held_at_its_bound() {
    // G = 4, b = 8, r^T W r = 20: the unbounded factor -2 removes 16 (80 %); held at -0.9 it
    // removes -2 (8)(-0.9) - 4 (0.81) = 11.16 (55.8 %)
    let free = localisation(vec![vec![4.0]], vec![8.0], 20.0, vec![]);
    let (t, e) = free.joint_fit(&[0]).unwrap();
    assert!(
        (t[0] + 2.0).abs() < 1e-15 && (e - 0.8).abs() < 1e-15,
        "{t:?} {e}"
    );
    let held = localisation(vec![vec![4.0]], vec![8.0], 20.0, vec![(-0.9, 2.0)]);
    let (t, e) = held.joint_fit(&[0]).unwrap();
    assert!((t[0] + 0.9).abs() < 1e-15, "{t:?}");
    assert!((e - 11.16 / 20.0).abs() < 1e-14, "{e}");
}

#[test]
fn two_coupled_groups_at_their_bounds() {
    // G = [[2, 1], [1, 2]], b = [3, -1], r^T W r = 10, both within [-0.5, 0.5]: the unbounded
    // minimum (-7/3, 5/3) leaves the box; at (-0.5, 0.5) the gradient 2 (b + G theta) = (5, -1)
    // points out of the box on both active bounds (KKT), so that corner is the minimum; it
    // removes -2 (3 (-0.5) - 0.5) - theta^T G theta = 4 - 0.5 = 3.5 (35 %)
    let loc = localisation(
        vec![vec![2.0, 1.0], vec![1.0, 2.0]],
        vec![3.0, -1.0],
        10.0,
        vec![(-0.5, 0.5), (-0.5, 0.5)],
    );
    let (t, e) = loc.joint_fit(&[0, 1]).unwrap();
    assert!(
        (t[0] + 0.5).abs() < 1e-14 && (t[1] - 0.5).abs() < 1e-14,
        "{t:?}"
    );
    assert!((e - 0.35).abs() < 1e-14, "{e}");
    // one bound active only: theta_1 in [-0.5, 0.5], theta_2 free: theta_1 = -0.5, then
    // theta_2 = -(b_2 + G_21 theta_1) / G_22 = 0.75, and the removed part
    // -2 (-1.5 - 0.75) - (0.5 - 0.75 + 1.125) = 4.5 - 0.875 = 3.625
    let one = localisation(
        vec![vec![2.0, 1.0], vec![1.0, 2.0]],
        vec![3.0, -1.0],
        10.0,
        vec![(-0.5, 0.5), (f64::NEG_INFINITY, f64::INFINITY)],
    );
    let (t, e) = one.joint_fit(&[0, 1]).unwrap();
    assert!(
        (t[0] + 0.5).abs() < 1e-13 && (t[1] - 0.75).abs() < 1e-13,
        "{t:?}"
    );
    assert!((e - 0.3625).abs() < 1e-13, "{e}");
}
