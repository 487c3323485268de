//! Naming a droid of a fleet as people write it: `@R2` in a mission, `R2` in a bridge's
//! topic. Case-insensitive; an exact name wins, then a model (`r2d2`, `BB-8`), then a unique
//! part of a name (`0001` for `D2-0001`, `R2` for `R2-D2 (simulated)`).

use super::FleetError;
use crate::model::Model;

/// One way a name may match: (lower-case name, model).
type Test<'a> = dyn Fn(&str, Model) -> bool + 'a;

/// The index in `droids` (name, model) that `asked` names.
pub fn resolve(droids: &[(&str, Model)], asked: &str) -> Result<usize, FleetError> {
    let a = asked.trim().to_lowercase();
    let one = |hits: Vec<usize>| -> Option<Result<usize, FleetError>> {
        match hits.len() {
            0 => None,
            1 => Some(Ok(hits[0])),
            _ => Some(Err(FleetError::Ambiguous {
                asked: asked.to_string(),
                matches: hits.iter().map(|i| droids[*i].0.to_string()).collect(),
            })),
        }
    };
    let matching = |f: &dyn Fn(&str, Model) -> bool| -> Vec<usize> {
        droids
            .iter()
            .enumerate()
            .filter(|(_, (n, m))| f(&n.to_lowercase(), *m))
            .map(|(i, _)| i)
            .collect()
    };
    if a.is_empty() {
        return Err(FleetError::NoSuchDroid {
            asked: asked.to_string(),
            names: droids.iter().map(|d| d.0.to_string()).collect(),
        });
    }
    let tries: [&Test; 3] = [
        &|n, _| n == a,
        &|_, m| m.id() == a || m.display_name().to_lowercase() == a,
        &|n, m| n.contains(&a) || m.display_name().to_lowercase().contains(&a),
    ];
    for t in tries {
        if let Some(r) = one(matching(t)) {
            return r;
        }
    }
    Err(FleetError::NoSuchDroid {
        asked: asked.to_string(),
        names: droids.iter().map(|d| d.0.to_string()).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const FLEET: [(&str, Model); 4] = [
        ("D2-0001", Model::R2D2),
        ("BB-0002", Model::BB8),
        ("Robi 42", Model::Robi42),
        ("Q5-0004", Model::R2Q5),
    ];

    #[test]
    fn exact_then_model_then_part() {
        assert_eq!(resolve(&FLEET, "d2-0001"), Ok(0));
        assert_eq!(resolve(&FLEET, "bb8"), Ok(1));
        assert_eq!(resolve(&FLEET, "BB-8"), Ok(1));
        assert_eq!(resolve(&FLEET, "robi"), Ok(2));
        assert_eq!(resolve(&FLEET, "0004"), Ok(3));
        assert_eq!(resolve(&FLEET, "r2-d2"), Ok(0));
    }

    #[test]
    fn ambiguous_and_unknown_say_what_there_is() {
        // "R2" is part of both R2-D2 and R2-Q5.
        let e = resolve(&FLEET, "R2").unwrap_err();
        assert!(matches!(&e, FleetError::Ambiguous { matches, .. } if matches.len() == 2));
        let e = resolve(&FLEET, "sprk").unwrap_err();
        assert!(e.to_string().contains("D2-0001, BB-0002"), "{e}");
        assert!(resolve(&FLEET, " ").is_err());
        // An exact name beats a part of another.
        let two = [("R2", Model::R2D2), ("R2-2", Model::R2D2)];
        assert_eq!(resolve(&two, "r2"), Ok(0));
    }
}
