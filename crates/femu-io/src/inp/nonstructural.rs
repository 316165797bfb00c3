//! `*NONSTRUCTURAL MASS`: mass that adds no stiffness, given per area of a set's shells and
//! membranes (their non-structural mass per area), per length of its beams and trusses, or in
//! total, spread over the set's shells and beams in proportion to their mass (`MASS
//! PROPORTIONAL`, Abaqus's default) or to their volume (`VOLUME PROPORTIONAL`: area times
//! thickness, length times area).

use super::orientation::dist;
use super::structural::at_err;
use super::*;
use femu_fem::structural::StructuralKind;

impl InpDeck {
    /// The deck's non-structural masses added to its shells' and beams' `nsm`.
    pub(super) fn apply_nonstructural(&self, model: &mut Model) -> Result<(), IoError> {
        for card in &self.nonstructural {
            let l = &card.line;
            let v = card
                .value
                .ok_or_else(|| at_err(l, "*NONSTRUCTURAL MASS without its data line".into()))?;
            if self
                .mesh
                .element_sets()
                .get(&card.elset)
                .is_some_and(|s| !s.is_empty())
            {
                return Err(at_err(
                    l,
                    format!(
                        "*NONSTRUCTURAL MASS on element set {}, which holds solid elements: femu spreads non-structural mass over shells and beams",
                        card.elset
                    ),
                ));
            }
            let members = model
                .structural_sets()
                .get(&card.elset)
                .cloned()
                .ok_or_else(|| {
                    at_err(
                        l,
                        format!(
                            "*NONSTRUCTURAL MASS names element set {}, which holds no shell or beam",
                            card.elset
                        ),
                    )
                })?;
            let coords = model.mesh().coords().to_vec();
            // each element's size (area or length) and the weight of its share of a total
            let mut sizes = Vec::with_capacity(members.len());
            for &i in &members {
                let el = &model.structural()[i];
                let x: Vec<[f64; 3]> = el.nodes.iter().map(|n| coords[*n]).collect();
                let (size, mass, volume) = match &el.kind {
                    StructuralKind::Shell(s) => {
                        let a = el.shell_area(&coords).expect("a shell");
                        (a, s.rho * s.t * a, s.t * a)
                    }
                    StructuralKind::Beam(b) => {
                        let end = |k: usize| -> [f64; 3] {
                            std::array::from_fn(|c| x[k][c] + b.offsets[k][c])
                        };
                        let len = dist(end(1), end(0));
                        let area = match &b.taper {
                            Some(end) => 0.5 * (b.section.area + end.area),
                            None => b.section.area,
                        };
                        (len, b.rho * area * len, area * len)
                    }
                    StructuralKind::Rod(r) => {
                        let len = dist(x[1], x[0]);
                        (len, r.rho * r.area * len, r.area * len)
                    }
                    other => {
                        return Err(at_err(
                            l,
                            format!(
                                "*NONSTRUCTURAL MASS on element {}, a {}: femu spreads non-structural mass over shells and beams",
                                el.id,
                                other.name()
                            ),
                        ));
                    }
                };
                sizes.push((size, if card.by_volume { volume } else { mass }));
            }
            let total: f64 = sizes.iter().map(|s| s.1).sum();
            if card.units == NsmUnits::Total && !(total > 0.0) {
                return Err(at_err(
                    l,
                    format!(
                        "*NONSTRUCTURAL MASS, UNITS=TOTAL MASS on set {}: its elements have no {} to share it by",
                        card.elset,
                        if card.by_volume { "volume" } else { "mass" }
                    ),
                ));
            }
            for (&i, &(size, weight)) in members.iter().zip(&sizes) {
                let mut el = model.structural()[i].clone();
                let id = el.id;
                let wrong = |units: &str, kind: &str| {
                    at_err(
                        l,
                        format!(
                            "*NONSTRUCTURAL MASS, UNITS={units} on element {id}, a {kind}: a mass per area is a shell's, per length a beam's"
                        ),
                    )
                };
                let per = |size: f64| match card.units {
                    NsmUnits::Total => v * weight / total / size,
                    _ => v,
                };
                match &mut el.kind {
                    StructuralKind::Shell(s) => {
                        if card.units == NsmUnits::PerLength {
                            return Err(wrong("MASS PER LENGTH", "shell"));
                        }
                        s.nsm += per(size);
                    }
                    StructuralKind::Beam(b) => {
                        if card.units == NsmUnits::PerArea {
                            return Err(wrong("MASS PER AREA", "beam"));
                        }
                        let add = per(size);
                        b.section.nsm += add;
                        if let Some(end) = &mut b.taper {
                            end.nsm += add;
                        }
                    }
                    StructuralKind::Rod(r) => {
                        if card.units == NsmUnits::PerArea {
                            return Err(wrong("MASS PER AREA", "truss"));
                        }
                        r.nsm += per(size);
                    }
                    _ => unreachable!("refused above"),
                }
                model
                    .set_structural(i, el)
                    .map_err(|source| IoError::Model {
                        path: l.path.clone(),
                        line: l.line,
                        source,
                    })?;
            }
        }
        Ok(())
    }
}
