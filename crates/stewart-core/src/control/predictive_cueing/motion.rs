//! The commanded motion the predictive method plans: the head's displacement from neutral
//! (inertial axes) and the cabin's attitude (1-2-3 angles), each a triple integrator driven by
//! its jerk, so the pose command and its first two derivatives are continuous whatever the
//! solves decide.

/// Channels: the head's x, y, z (m), then roll, pitch, yaw (rad).
pub const CHANNELS: usize = 6;

/// Position, rate and acceleration of each channel.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CommandedMotion {
    /// Head displacement (m) and angles (rad).
    pub position: [f64; CHANNELS],
    /// Their rates (m/s, rad/s).
    pub rate: [f64; CHANNELS],
    /// Their accelerations (m/s², rad/s²).
    pub acceleration: [f64; CHANNELS],
}

/// How a triple integrator's position, rate and acceleration answer a jerk held over `h`:
/// `(h³/6, h²/2, h)`.
#[inline]
pub fn jerk_response(h: f64) -> [f64; 3] {
    [h * h * h / 6.0, h * h / 2.0, h]
}

impl CommandedMotion {
    /// Advances exactly over `h` with the jerks `jerk` held.
    pub fn advance(&mut self, jerk: &[f64; CHANNELS], h: f64) {
        let [p3, p2, p1] = jerk_response(h);
        for c in 0..CHANNELS {
            let (x, v, a) = (self.position[c], self.rate[c], self.acceleration[c]);
            self.position[c] = x + v * h + a * (h * h / 2.0) + jerk[c] * p3;
            self.rate[c] = v + a * h + jerk[c] * p2;
            self.acceleration[c] = a + jerk[c] * p1;
        }
    }

    /// The head's displacement, velocity and acceleration.
    pub fn head(&self) -> ([f64; 3], [f64; 3], [f64; 3]) {
        let pick = |x: &[f64; CHANNELS]| [x[0], x[1], x[2]];
        (pick(&self.position), pick(&self.rate), pick(&self.acceleration))
    }

    /// The angles, their rates and accelerations.
    pub fn attitude(&self) -> ([f64; 3], [f64; 3], [f64; 3]) {
        let pick = |x: &[f64; CHANNELS]| [x[3], x[4], x[5]];
        (pick(&self.position), pick(&self.rate), pick(&self.acceleration))
    }

    pub fn to_array(&self) -> [f64; 3 * CHANNELS] {
        let mut x = [0.0; 3 * CHANNELS];
        x[..CHANNELS].copy_from_slice(&self.position);
        x[CHANNELS..2 * CHANNELS].copy_from_slice(&self.rate);
        x[2 * CHANNELS..].copy_from_slice(&self.acceleration);
        x
    }

    pub fn from_array(x: &[f64; 3 * CHANNELS]) -> Self {
        let part = |at: usize| std::array::from_fn(|c| x[at + c]);
        CommandedMotion { position: part(0), rate: part(CHANNELS), acceleration: part(2 * CHANNELS) }
    }

    pub fn is_finite(&self) -> bool {
        self.to_array().iter().all(|x| x.is_finite())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two half steps are one step, and the position is the cubic of the jerk.
    #[test]
    fn the_integrators_are_exact() {
        let mut m = CommandedMotion { position: [0.1; 6], rate: [-0.2; 6], acceleration: [0.3; 6] };
        let mut halves = m;
        let jerk = [1.0, -2.0, 0.5, 0.1, -0.3, 0.0];
        m.advance(&jerk, 0.2);
        halves.advance(&jerk, 0.1);
        halves.advance(&jerk, 0.1);
        for c in 0..CHANNELS {
            let t = 0.2;
            let p = 0.1 - 0.2 * t + 0.3 * t * t / 2.0 + jerk[c] * t * t * t / 6.0;
            assert!((m.position[c] - p).abs() < 1e-15 && (halves.position[c] - p).abs() < 1e-15);
            assert!((m.rate[c] - halves.rate[c]).abs() < 1e-15);
        }
    }
}
