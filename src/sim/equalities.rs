//! The model's own loop constraints in a simulation (MJCF `<equality>`,
//! mjcf.md §"Details": `Model::equalities`): a [`Simulation`] starts with them
//! as it would with a scene's `"constraints"` ([`Simulation::set_constraints`],
//! src/sim/loops/mod.rs), those marked inactive switched off
//! ([`Simulation::set_constraint_active`] turns them on).

use super::{SimError, Simulation};

impl Simulation {
    /// Adds the model's equalities to the run (nothing when it has none);
    /// returns one line for each active one the current state violates by more
    /// than 1 mm ([`Simulation::set_constraints`]).
    pub fn set_model_equalities(&mut self) -> Result<Vec<String>, SimError> {
        if self.model.equalities.items.is_empty() {
            return Ok(Vec::new());
        }
        let set = self.model.equalities.clone();
        let off: Vec<String> = set
            .items
            .iter()
            .zip(
                self.model
                    .equality_active
                    .iter()
                    .chain(std::iter::repeat(&true)),
            )
            .filter(|(_, on)| !**on)
            .map(|(c, _)| c.name.clone())
            .collect();
        let lines = self.set_constraints(set)?;
        for name in &off {
            self.set_constraint_active(name, false)?;
        }
        Ok(lines
            .into_iter()
            .filter(|l| {
                !off.iter()
                    .any(|n| l.starts_with(&format!("constraint \"{n}\"")))
            })
            .collect())
    }

    /// One line for each active loop constraint the current state violates by
    /// more than 1 mm (what [`Simulation::set_constraints`] reports, for a start
    /// set after it: an MJCF `--key` or `--initial`).
    pub fn constraint_start_lines(&mut self) -> Vec<String> {
        let Some(l) = self.cons.loops.as_ref() else {
            return Vec::new();
        };
        let (set, active) = (l.set.clone(), l.active.clone());
        let mut out = vec![0.0; set.items.len()];
        let q = self.q.clone();
        if crate::dynamics::constraint_violation(&self.model, &mut self.data, &set, &q, &mut out)
            .is_err()
        {
            return Vec::new();
        }
        self.fk_valid = true;
        set.items
            .iter()
            .zip(out)
            .zip(active)
            .filter(|((_, x), on)| *on && x.abs() > 1e-3)
            .map(|((c, x), _)| {
                format!(
                    "constraint \"{}\" ({}) is violated by {:.3e} at the start: the run closes it gently",
                    c.name,
                    c.kind_name(),
                    x.abs()
                )
            })
            .collect()
    }
}
