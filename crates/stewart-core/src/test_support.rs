//! What the unit tests of several modules share: a seeded pseudo-random sequence and the
//! workspace of the default stand with the truck cabin's neutral.

use crate::physics::cueing::limiter::Workspace;
use crate::physics::stand::Stand;

/// xorshift64 from `seed`, uniform in [-1, 1) (53 bits; reproducible on every platform).
pub fn xorshift(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

/// The default stand's legs with margins inside 1.48..2.12 m about the truck cabin's neutral,
/// the limiter's onset at 0.8.
pub fn truck_workspace() -> Workspace {
    let stand = Stand::default();
    Workspace {
        base_joints: stand.base_joints,
        platform_joints: stand.platform_joints,
        lower: [1.48; 6],
        upper: [2.12; 6],
        neutral: Stand::truck_cabin_neutral_position(),
        onset: 0.8,
    }
}
