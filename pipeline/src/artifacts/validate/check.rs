//! The checks of one file, each naming the file and the field of what it
//! refuses.

use crate::artifacts::field::Field;
use crate::artifacts::{CompiledDir, invalid};
use crate::error::{ArtifactProblem as P, PipelineError, Result};
use std::collections::HashMap;
use std::fmt::Display;
use std::path::PathBuf;

/// The checks of one file: their errors name it.
pub(super) struct Check {
    file: PathBuf,
}

impl Check {
    pub(super) fn of(c: &CompiledDir, name: &str) -> Check {
        Check {
            file: c.dir.join(name),
        }
    }

    pub(super) fn fail(&self, at: &Field, problem: P) -> PipelineError {
        invalid(&self.file, at, problem)
    }

    /// Finite, and within what the single-precision computations
    /// downstream hold.
    pub(super) fn finite(&self, at: &Field, v: f64) -> Result<()> {
        if v.is_finite() && v.abs() <= f64::from(f32::MAX) {
            Ok(())
        } else {
            Err(self.fail(at, P::NotFinite { value: v }))
        }
    }

    pub(super) fn point(&self, at: &Field, v: &[f64]) -> Result<()> {
        for (i, &x) in v.iter().enumerate() {
            self.finite(&at.index(i), x)?;
        }
        Ok(())
    }

    pub(super) fn above(&self, at: &Field, v: f64, bound: f64) -> Result<()> {
        self.finite(at, v)?;
        if v > bound {
            Ok(())
        } else {
            Err(self.fail(at, P::NotAbove { value: v, bound }))
        }
    }

    /// Every dimension finite and positive.
    pub(super) fn size(&self, at: &Field, v: &[f64]) -> Result<()> {
        for (i, &x) in v.iter().enumerate() {
            self.above(&at.index(i), x, 0.0)?;
        }
        Ok(())
    }

    pub(super) fn length_in(&self, at: &Field, v: f64, range: (f64, f64)) -> Result<()> {
        self.within(at, v, range, |value, min, max| P::LengthOutOfRange {
            value,
            min,
            max,
        })
    }

    pub(super) fn share_in(&self, at: &Field, v: f64, range: (f64, f64)) -> Result<()> {
        self.within(at, v, range, |value, min, max| P::ShareOutOfRange {
            value,
            min,
            max,
        })
    }

    pub(super) fn time_in(&self, at: &Field, v: f64, range: (f64, f64)) -> Result<()> {
        self.within(at, v, range, |value, min, max| P::TimeOutOfRange {
            value,
            min,
            max,
        })
    }

    pub(super) fn limit_in(&self, at: &Field, v: f64, range: (f64, f64)) -> Result<()> {
        self.within(at, v, range, |value, min, max| P::LimitOutOfRange {
            value,
            min,
            max,
        })
    }

    /// `v` finite and in `min..=max`, else the problem `outside` names.
    fn within(
        &self,
        at: &Field,
        v: f64,
        (min, max): (f64, f64),
        outside: fn(f64, f64, f64) -> P,
    ) -> Result<()> {
        self.finite(at, v)?;
        if (min..=max).contains(&v) {
            Ok(())
        } else {
            Err(self.fail(at, outside(v, min, max)))
        }
    }

    pub(super) fn count(&self, at: &Field, found: usize, expected: usize) -> Result<()> {
        if found == expected {
            Ok(())
        } else {
            Err(self.fail(at, P::CountMismatch { expected, found }))
        }
    }

    pub(super) fn differs(
        &self,
        at: &Field,
        found: impl Display,
        expected: impl Display,
    ) -> PipelineError {
        self.fail(
            at,
            P::Differs {
                expected: expected.to_string(),
                found: found.to_string(),
            },
        )
    }

    /// `name` (at `at`) is `expected`, the name of a record it belongs to.
    pub(super) fn same_name(
        &self,
        at: &Field,
        name: &str,
        expected: &str,
        whose: &str,
    ) -> Result<()> {
        if name == expected {
            Ok(())
        } else {
            Err(self.differs(at, format!("`{name}`"), format!("`{expected}` ({whose})")))
        }
    }

    pub(super) fn unknown(&self, at: &Field, what: &'static str, name: &str) -> PipelineError {
        self.fail(
            at,
            P::UnknownName {
                what,
                name: name.to_owned(),
            },
        )
    }

    /// The index of each name of `names` (at `list[i].key`), refusing a
    /// name given twice.
    pub(super) fn unique<'n>(
        &self,
        list: &Field,
        key: &str,
        what: &'static str,
        names: impl Iterator<Item = &'n str>,
    ) -> Result<HashMap<&'n str, usize>> {
        let mut index = HashMap::new();
        for (i, name) in names.enumerate() {
            if index.insert(name, i).is_some() {
                return Err(self.fail(
                    &list.index(i).key(key),
                    P::Duplicate {
                        what,
                        name: name.to_owned(),
                    },
                ));
            }
        }
        Ok(index)
    }

    /// Each of `names` (at `list[i]`) is one of `allowed` and not given
    /// before in `names` or in `seen`, which it joins.
    pub(super) fn names_of<'n>(
        &self,
        list: &Field,
        names: &'n [String],
        allowed: &[&str],
        what: &'static str,
        seen: &mut Vec<&'n str>,
    ) -> Result<()> {
        for (i, name) in names.iter().enumerate() {
            let at = list.index(i);
            if !allowed.contains(&name.as_str()) {
                return Err(self.unknown(&at, what, name));
            }
            if seen.contains(&name.as_str()) {
                return Err(self.fail(
                    &at,
                    P::Duplicate {
                        what,
                        name: name.clone(),
                    },
                ));
            }
            seen.push(name);
        }
        Ok(())
    }
}
