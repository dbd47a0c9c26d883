//! The paper's non-dimensional units (section 4) and mechanical similarity (textbook 1.4).
//!
//! Unit of length `R_b` (base joint circle radius), of mass `M`, of force `M g`, of time
//! `1/omega` with `omega = sqrt(g / R_b)`. In these units `M = 1`, `g = 1`, and the equations
//! keep their form, so the same code computes the non-dimensional problem directly.

use super::stand::Stand;

/// Units of a similarity transformation: a quantity `q` in SI is `q / unit` non-dimensionally.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scales {
    /// m
    pub length: f64,
    /// kg
    pub mass: f64,
    /// s
    pub time: f64,
}

impl Scales {
    /// The paper's units for a stand: `R_b`, `M`, `sqrt(R_b / g)`.
    pub fn paper(stand: &Stand) -> Self {
        let length = stand.base_radius();
        Scales { length, mass: stand.mass, time: (length / stand.gravity).sqrt() }
    }
    /// N
    pub fn force(&self) -> f64 {
        self.mass * self.length / (self.time * self.time)
    }
    /// m/s
    pub fn velocity(&self) -> f64 {
        self.length / self.time
    }
    /// kg m²
    pub fn inertia(&self) -> f64 {
        self.mass * self.length * self.length
    }
    /// J
    pub fn energy(&self) -> f64 {
        self.force() * self.length
    }
    /// 1/s
    pub fn rate(&self) -> f64 {
        1.0 / self.time
    }

    /// The stand expressed in these units.
    pub fn nondimensional_stand(&self, stand: &Stand) -> Stand {
        Stand {
            mass: stand.mass / self.mass,
            inertia: stand.inertia.map(|j| j / self.inertia()),
            gravity: stand.gravity * self.time * self.time / self.length,
            base_joints: stand.base_joints.map(|b| b / self.length),
            platform_joints: stand.platform_joints.map(|a| a / self.length),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_units_make_mass_and_gravity_one() {
        let stand = Stand::truck_cabin();
        let nd = Scales::paper(&stand).nondimensional_stand(&stand);
        assert!((nd.mass - 1.0).abs() < 1e-15);
        assert!((nd.gravity - 1.0).abs() < 1e-15);
        assert!((nd.base_radius() - 1.0).abs() < 1e-15);
        assert!((nd.inertia[2] - 2200.0 / (3000.0 * 2.25)).abs() < 1e-15);
    }
}
