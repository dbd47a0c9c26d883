//! The legs as bodies (docs/model.md §8): each leg is a cylinder hinged at `B_k` and a rod
//! hinged at `A_k`, sliding in the cylinder along the leg direction `n_k`. Both are
//! axisymmetric about the leg axis; their spin about it is ignored. All six legs are alike.
//!
//! With `c_k = B_k + d_c n_k` and `p_k = a_k - d_r n_k` the bodies' centres of mass, the leg's
//! kinetic and potential energy are
//!
//! ```text
//! T_k = 1/2 (m_r + m_a) l'^2 + 1/2 I_t(l) |n'|^2,    I_t(l) = m_c d_c^2 + m_r (l - d_r)^2 + J_c + J_r
//! V_k = g (m_c c_k,z + m_r p_k,z)
//! ```
//!
//! (`I_t`: the leg's transverse moment of inertia about `B_k`). Lagrange's equations for the
//! leg's coordinates `(l, n)`, with the force `-F` of the platform at `a_k` and the axial force
//! `s` (actuator, friction, end stop) between the bodies, give the force of the leg on the
//! platform:
//!
//! ```text
//! F = s n + b - ((m_r + m_a) n n^T + I_t / l^2 P) a''          P = I - n n^T
//! b = -(m_r d_r |n'|^2 + m_a l |n'|^2 + m_r g n_z) n + (2 l' / l^2)(m_c d_c^2 + J_c + J_r - m_r d_r (l - d_r)) n'
//!     - (g / l)(m_r (l - d_r) + m_c d_c) P ez
//! ```
//!
//! plus the joint-limit moments' transverse forces ([`super::joint_limits`]). The term in
//! `a''`, the joint's acceleration, is the leg's inertia seen at the platform joint: it makes
//! the platform's accelerations the solution of a 6x6 linear system
//! (`crate::physics::special_form`). With no mass and no inertia, `F = s n`: the paper's
//! massless two-force member.

use nalgebra::Vector3;

use crate::physics::error::ParameterError;
use crate::physics::number::{Number, Real};

/// Default distance of the cylinder's centre of mass from `B_k`, m: half the default stand's
/// shortest leg (1.45 m), a barrel of about that length.
pub const DEFAULT_CYLINDER_COM: f64 = 0.5;
/// Default distance of the rod's centre of mass from `A_k`, m: half its free length at the
/// default stroke (0.7 m) plus the part inside the barrel.
pub const DEFAULT_ROD_COM: f64 = 0.5;

/// The leg bodies' parameters (`leg.*`), the same for all six legs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LegBodies {
    /// `m_c`, kg.
    pub cylinder_mass: f64,
    /// `m_r`, kg.
    pub rod_mass: f64,
    /// `d_c`, m, from `B_k` along the leg.
    pub cylinder_com: f64,
    /// `d_r`, m, from `A_k` back along the leg.
    pub rod_com: f64,
    /// `J_c`, kg m², transverse, about the cylinder's centre of mass.
    pub cylinder_inertia: f64,
    /// `J_r`, kg m², transverse, about the rod's centre of mass.
    pub rod_inertia: f64,
    /// `m_a`, kg: inertia moving with the leg's length alone, the electric drive's rotor
    /// reflected along the leg (`J_m N²`, docs/model.md §9; set from the drives, 0 without):
    /// kinetic energy `1/2 m_a l'²`.
    pub axial_mass: f64,
}

impl Default for LegBodies {
    /// Massless legs (the paper's).
    fn default() -> Self {
        LegBodies {
            cylinder_mass: 0.0,
            rod_mass: 0.0,
            cylinder_com: DEFAULT_CYLINDER_COM,
            rod_com: DEFAULT_ROD_COM,
            cylinder_inertia: 0.0,
            rod_inertia: 0.0,
            axial_mass: 0.0,
        }
    }
}

/// One leg's length, direction and their rates.
#[derive(Clone, Copy, Debug)]
pub struct LegMotion<T: nalgebra::Scalar> {
    /// `l`, m.
    pub l: T,
    /// `n`, unit.
    pub n: Vector3<T>,
    /// `l'`, m/s.
    pub l_dot: T,
    /// `n' = (a' - l' n) / l`, 1/s.
    pub n_dot: Vector3<T>,
}

impl<T: Real> LegMotion<T> {
    /// From the leg vector `q = a - B` (length `l > 0`) and the joint's velocity `a'`.
    #[inline]
    pub fn new(q: &Vector3<T>, l: T, a_dot: &Vector3<T>) -> Self {
        let n = q / l;
        let l_dot = n.dot(a_dot);
        LegMotion { l, n, l_dot, n_dot: (a_dot - n * l_dot) / l }
    }

    /// The leg to platform joint `a` (body frame) of a body state: its vector `q` (length
    /// `l > 0`), the joint's velocity and the length's rate by the one law of the legs
    /// ([`crate::physics::legs::geometry::joint_rate`]; the direction `q / l`, divided, as the
    /// legs as bodies always took it).
    #[inline]
    pub fn at(state: &crate::physics::body::state::BodyState<T>, a: &Vector3<f64>, q: &Vector3<T>, l: T) -> Self {
        let n = q / l;
        let (l_dot, a_dot) = crate::physics::legs::geometry::joint_rate(state, a, &n);
        LegMotion { l, n, l_dot, n_dot: (a_dot - n * l_dot) / l }
    }
}

/// A leg's inertia seen at the platform joint: `F = ... + bias - (along n n^T + across P) a''`.
#[derive(Clone, Copy, Debug)]
pub struct LegInertia<T: nalgebra::Scalar> {
    /// `m_r + m_a`, kg: the mass the joint drags along the leg.
    pub along: T,
    /// `I_t / l^2`, kg: across the leg.
    pub across: T,
    /// The force `b` independent of the joint's acceleration, N.
    pub bias: Vector3<T>,
}

impl<T: Real> LegInertia<T> {
    /// `(along n n^T + across P) x`.
    #[inline]
    pub fn times(&self, n: &Vector3<T>, x: &Vector3<T>) -> Vector3<T> {
        let along = n.dot(x);
        x * self.across + n * (along * (self.along - self.across))
    }
}

impl LegBodies {
    /// Whether the legs have mass or inertia (else they are the paper's two-force members).
    pub fn has_mass(&self) -> bool {
        self.cylinder_mass != 0.0
            || self.rod_mass != 0.0
            || self.cylinder_inertia != 0.0
            || self.rod_inertia != 0.0
            || self.axial_mass != 0.0
    }

    /// Whether the legs resist turning (`I_t != 0`: a rod mass, a cylinder's mass away from
    /// `B_k`, or either body's inertia), as more than the mass along them.
    #[inline(always)]
    pub fn has_transverse_inertia(&self) -> bool {
        self.rod_mass != 0.0
            || self.cylinder_mass * self.cylinder_com * self.cylinder_com + self.cylinder_inertia + self.rod_inertia
                != 0.0
    }

    /// `I_t(l)`, kg m².
    #[inline(always)]
    pub fn transverse_inertia<T: Number>(&self, l: T) -> T {
        let rod = l - self.rod_com;
        rod * rod * self.rod_mass
            + (self.cylinder_mass * self.cylinder_com * self.cylinder_com + self.cylinder_inertia + self.rod_inertia)
    }

    /// The leg's inertia and its force on the platform apart from the axial force and the
    /// joint's acceleration (the module's `b`), under gravity `g` along `-z`.
    #[inline]
    pub fn inertia<T: Real>(&self, leg: &LegMotion<T>, g: f64) -> LegInertia<T> {
        let LegMotion { l, n, l_dot, n_dot } = *leg;
        let (across, bias) = self.inertia_terms(l, &[n.x, n.y, n.z], l_dot, &[n_dot.x, n_dot.y, n_dot.z], g);
        LegInertia { along: T::constant(self.rod_mass + self.axial_mass), across, bias: Vector3::from(bias) }
    }

    /// The law of [`LegBodies::inertia`] for a leg of length `l`, direction `n` and their rates
    /// in any number type (one leg in `f64` or `Dual`, or the six side by side): `across`
    /// (`I_t / l^2`, kg) and the force `b` (N). `along` is the constant `m_r + m_a`.
    #[inline(always)]
    pub fn inertia_terms<T: Number>(&self, l: T, n: &[T; 3], l_dot: T, n_dot: &[T; 3], g: f64) -> (T, [T; 3]) {
        let (m_r, d_r) = (self.rod_mass, self.rod_com);
        let axial = self.axial_force(l, n, n_dot, g);
        let fixed =
            self.cylinder_mass * self.cylinder_com * self.cylinder_com + self.cylinder_inertia + self.rod_inertia;
        let inverse = T::constant(1.0) / l;
        let inverse2 = inverse * inverse;
        let swing = l_dot * inverse2 * ((T::constant(fixed) - (l - d_r) * (m_r * d_r)) * 2.0);
        let lever = ((l - d_r) * m_r + self.cylinder_mass * self.cylinder_com) * g * inverse;
        // `P ez = ez - n n_z`.
        let vertical = [n[0] * n[2] * -1.0, n[1] * n[2] * -1.0, T::constant(1.0) - n[2] * n[2]];
        // Written out, not `from_fn`: a closure over vector lanes is not inlined.
        let bias = [
            n[0] * axial + n_dot[0] * swing - vertical[0] * lever,
            n[1] * axial + n_dot[1] * swing - vertical[1] * lever,
            n[2] * axial + n_dot[2] * swing - vertical[2] * lever,
        ];
        (self.transverse_inertia(l) * inverse2, bias)
    }

    /// The part of `b` along the leg that its mass moving along it gives, N (the whole `b`
    /// where the legs have no [transverse inertia](LegBodies::has_transverse_inertia): the
    /// drives' rotors alone): the rod's centripetal term and weight, and the axial mass's
    /// `m_a l |n'|^2` (its coordinate is `l`, with `l'' = n . a'' + l |n'|^2`).
    #[inline(always)]
    pub fn axial_force<T: Number>(&self, l: T, n: &[T; 3], n_dot: &[T; 3], g: f64) -> T {
        let (m_r, d_r) = (self.rod_mass, self.rod_com);
        let n_dot2 = n_dot[0] * n_dot[0] + n_dot[1] * n_dot[1] + n_dot[2] * n_dot[2];
        (n_dot2 * (l * self.axial_mass + m_r * d_r) + n[2] * (m_r * g)) * -1.0
    }

    /// The leg's kinetic and gravitational potential energy, J (`base_z`: the height of
    /// `B_k`).
    pub fn energy<T: Real>(&self, leg: &LegMotion<T>, base_z: f64, g: f64) -> T {
        let LegMotion { l, n, l_dot, n_dot } = *leg;
        let kinetic = l_dot * l_dot * (0.5 * (self.rod_mass + self.axial_mass))
            + self.transverse_inertia(l) * n_dot.dot(&n_dot) * 0.5;
        let cylinder_z = n.z * self.cylinder_com + base_z;
        let rod_z = n.z * (l - self.rod_com) + base_z;
        kinetic + (cylinder_z * self.cylinder_mass + rod_z * self.rod_mass) * g
    }

    /// Checks the parameters (FMI names in the errors).
    pub fn validate(&self) -> Result<(), ParameterError> {
        for (name, value) in [
            ("leg.cylinderMass", self.cylinder_mass),
            ("leg.rodMass", self.rod_mass),
            ("leg.cylinderCoM", self.cylinder_com),
            ("leg.rodCoM", self.rod_com),
            ("leg.cylinderInertia", self.cylinder_inertia),
            ("leg.rodInertia", self.rod_inertia),
            ("motor.J", self.axial_mass),
        ] {
            crate::physics::stand::check_finite(name, value)?;
            if value < 0.0 {
                return Err(ParameterError::new(name, format!("must be >= 0, got {value:e}")));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::number::Dual;

    /// The force of a leg moving freely (no axial force, its joint's acceleration given) is
    /// the leg's rate of momentum plus gravity, by Lagrange: checked against the energy.
    /// The power the platform receives, `F . a'`, equals `-d(T + V)/dt` of the leg.
    #[test]
    fn the_legs_force_on_the_platform_does_the_work_its_energy_loses() {
        let legs = LegBodies {
            cylinder_mass: 40.0,
            rod_mass: 15.0,
            cylinder_com: 0.45,
            rod_com: 0.55,
            cylinder_inertia: 2.5,
            rod_inertia: 0.8,
            axial_mass: 120.0,
        };
        let g = 9.81;
        let base = Vector3::new(0.3, -1.2, 0.1);
        // A joint path a(t) with velocity and acceleration, through duals in time.
        let path =
            |t: Dual| Vector3::new((t * 1.3).tanh() * 0.4 + 0.5, (t * t) * 0.2 - 1.0, (t * 0.7).exp() * 0.3 + 1.5);
        for t in [0.0, 0.3, 1.1] {
            let p = path(Dual::new(t, 1.0));
            let (a, a_dot) = (p.map(|d| d.re), p.map(|d| d.eps));
            let h = 1e-5;
            let acc =
                (path(Dual::new(t + h, 1.0)).map(|d| d.eps) - path(Dual::new(t - h, 1.0)).map(|d| d.eps)) / (2.0 * h);
            let energy = |t: f64| {
                let p = path(Dual::new(t, 1.0));
                let q = p.map(|d| d.re) - base;
                let l = q.norm();
                legs.energy(&LegMotion::new(&q, l, &p.map(|d| d.eps)), base.z, g)
            };
            let q = a - base;
            let leg = LegMotion::new(&q, q.norm(), &a_dot);
            let inertia = legs.inertia(&leg, g);
            let force = inertia.bias - inertia.times(&leg.n, &acc);
            let power = force.dot(&a_dot);
            let energy_rate = (energy(t + h) - energy(t - h)) / (2.0 * h);
            println!("t = {t}: power {power:.9e} W, -dE/dt {:.9e} W", -energy_rate);
            assert!((power + energy_rate).abs() < 1e-6 * (1.0 + energy_rate.abs()), "{power} vs {energy_rate}");
        }
    }
}
