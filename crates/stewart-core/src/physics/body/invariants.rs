//! Quantities conserved or constrained by the exact motion: energy, momenta, the constraint
//! residual. The textbook (section 1.3) uses them to check a model's correctness.

use nalgebra::Vector3;

use super::state::BodyState;
use crate::physics::number::{Real, lift};
use crate::physics::stand::Stand;

/// Kinetic energy `M v²/2 + w.J w/2`, J.
pub fn kinetic_energy<T: Real>(stand: &Stand, state: &BodyState<T>) -> T {
    let w = state.angular_velocity_body();
    let jw = lift::<T>(&Vector3::from(stand.inertia)).component_mul(&w);
    state.v.dot(&state.v) * (0.5 * stand.mass) + w.dot(&jw) * 0.5
}

/// Gravitational potential energy `M g z`, J (zero at the base plane).
pub fn potential_energy<T: Real>(stand: &Stand, state: &BodyState<T>) -> T {
    state.r.z * (stand.mass * stand.gravity)
}

/// Kinetic plus gravitational potential energy, J (the FMU output `E`).
pub fn mechanical_energy<T: Real>(stand: &Stand, state: &BodyState<T>) -> T {
    kinetic_energy(stand, state) + potential_energy(stand, state)
}

/// Linear momentum `M v`, kg m/s.
pub fn linear_momentum(stand: &Stand, state: &BodyState) -> Vector3<f64> {
    state.v * stand.mass
}

/// Angular momentum about the inertial origin `r x M v + R J w`, kg m²/s.
pub fn angular_momentum(stand: &Stand, state: &BodyState) -> Vector3<f64> {
    let w = state.angular_velocity_body();
    let j = Vector3::from(stand.inertia);
    state.r.cross(&(state.v * stand.mass)) + state.rotation() * j.component_mul(&w)
}
