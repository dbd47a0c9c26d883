//! Quantities conserved or constrained by the exact motion: energy, momenta, the constraint
//! residual. The textbook (section 1.3) uses them to check a model's correctness.

use nalgebra::Vector3;

use super::body_state::BodyState;
use super::stand::Stand;

/// Kinetic energy `M v²/2 + w.J w/2`, J.
pub fn kinetic_energy(stand: &Stand, state: &BodyState) -> f64 {
    let w = state.angular_velocity_body();
    let j = Vector3::from(stand.inertia);
    0.5 * stand.mass * state.v.norm_squared() + 0.5 * w.dot(&j.component_mul(&w))
}

/// Gravitational potential energy `M g z`, J (zero at the base plane).
pub fn potential_energy(stand: &Stand, state: &BodyState) -> f64 {
    stand.mass * stand.gravity * state.r.z
}

/// Kinetic plus gravitational potential energy, J (the FMU output `E`).
pub fn mechanical_energy(stand: &Stand, state: &BodyState) -> f64 {
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
