//! Outputs recorded at an interval: every `every`-th communication point, the named Real
//! variables, in one flat row-major table.

use crate::system::{Observer, Readings, System};

pub struct Recorder {
    watched: Vec<Vec<u32>>,
    /// Per column: (component, position in its watched list).
    columns: Vec<(usize, usize)>,
    every: usize,
    pub times: Vec<f64>,
    /// Row-major: one row of `columns.len()` values per recorded point.
    pub values: Vec<f64>,
}

impl Recorder {
    /// Records `names` ("component.variable", Real) every `every` steps (`every` >= 1).
    pub fn new(system: &System, names: &[String], every: usize) -> Result<Recorder, String> {
        let mut watched = vec![vec![]; system.component_count()];
        let mut columns = vec![];
        for name in names {
            let (c, vr, kind) = system.resolve(name)?;
            if kind != crate::description::Type::Real {
                return Err(format!("{name}: only Real variables can be recorded"));
            }
            let list: &mut Vec<u32> = &mut watched[c];
            let position = list.iter().position(|&v| v == vr).unwrap_or_else(|| {
                list.push(vr);
                list.len() - 1
            });
            columns.push((c, position));
        }
        Ok(Recorder { watched, columns, every: every.max(1), times: vec![], values: vec![] })
    }

    pub fn width(&self) -> usize {
        self.columns.len()
    }
}

impl Observer for Recorder {
    fn watched(&self) -> Vec<Vec<u32>> {
        self.watched.clone()
    }

    fn step(&mut self, step: usize, time: f64, values: &Readings) {
        if (step + 1) % self.every == 0 {
            self.times.push(time);
            for &(c, i) in &self.columns {
                self.values.push(values.of(c)[i]);
            }
        }
    }
}
