//! The continuous states a variable table declares, in the order of the state vector: derived
//! at compile time from the derivative declarations (a state group is one whose derivative
//! group names it), so that the model's `STATES` follow the declarations.

use super::VariableGroup;

/// The number of continuous states a variable table declares: the elements of every group that
/// a derivative group names (`derivative`, `derivative_named`).
pub const fn state_count(groups: &[VariableGroup]) -> usize {
    let mut count = 0;
    let mut i = 0;
    while i < groups.len() {
        if let Some(state) = groups[i].derivative_of {
            count += element_count(groups[named(groups, state)].shape);
        }
        i += 1;
    }
    count
}

/// The continuous states, `(group name, flat element index)` in the order of the state vector:
/// the state groups in the order their derivatives are declared, each element by element
/// (column by column where the group says so). The declarations must follow the simulation's
/// layout (`crate::simulation::state`); `state_order_tests` holds the two together. A
/// derivative of another shape than its state, a state named by two derivatives, or a state
/// column by column that is not a matrix is a build error.
pub const fn states<const N: usize>(groups: &[VariableGroup]) -> [(&'static str, usize); N] {
    let mut states = [("", 0); N];
    let mut n = 0;
    let mut i = 0;
    while i < groups.len() {
        if let Some(name) = groups[i].derivative_of {
            let state = &groups[named(groups, name)];
            assert!(same_shape(state.shape, groups[i].shape), "a derivative has another shape than its state");
            assert!(!state.state_by_columns || state.shape.len() == 2, "only a matrix is a state column by column");
            let mut earlier = 0;
            while earlier < i {
                if let Some(other) = groups[earlier].derivative_of {
                    assert!(!same(other, name), "two derivatives name one state group");
                }
                earlier += 1;
            }
            let count = element_count(state.shape);
            let mut k = 0;
            while k < count {
                states[n] = (state.name, if state.state_by_columns { column_major(state.shape, k) } else { k });
                n += 1;
                k += 1;
            }
        }
        i += 1;
    }
    assert!(n == N, "state_count and states disagree");
    states
}

const fn same_shape(a: &[usize], b: &[usize]) -> bool {
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

const fn element_count(shape: &[usize]) -> usize {
    let mut count = 1;
    let mut i = 0;
    while i < shape.len() {
        count *= shape[i];
        i += 1;
    }
    count
}

/// The flat (row-major) index of element `k` of a matrix counted column by column.
const fn column_major(shape: &[usize], k: usize) -> usize {
    assert!(shape.len() == 2, "only a matrix is a state column by column");
    let rows = shape[0];
    (k % rows) * shape[1] + k / rows
}

/// The index of the group named `name` (a compile-time error if none is).
// Evaluated when the tables are compiled (`STATES` is a static): the panic is a build error.
#[allow(clippy::panic)]
const fn named(groups: &[VariableGroup], name: &str) -> usize {
    let mut i = 0;
    while i < groups.len() {
        if same(groups[i].name, name) {
            return i;
        }
        i += 1;
    }
    panic!("a derivative names a state group that is not declared")
}

const fn same(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

#[cfg(test)]
mod state_order_tests {
    use super::{VariableGroup as V, column_major, state_count, states};
    use crate::physics::body::state::STATE_DIM;
    use crate::simulation::SIMULATION_DIM;
    use crate::simulation::state::{CURRENTS, hydraulic, quadrature};

    /// Where `(group, element)` sits in a model's derived state vector.
    fn index(table: &[(&str, usize)], group: &str, element: usize) -> usize {
        table.iter().position(|&s| s == (group, element)).unwrap_or_else(|| panic!("{group}[{element}] is no state"))
    }

    #[test]
    fn a_matrix_column_by_column_counts_down_each_column_first() {
        let order: Vec<usize> = (0..6).map(|k| column_major(&[2, 3], k)).collect();
        assert_eq!(order, [0, 3, 1, 4, 2, 5]);
        const TABLE: &[V] = &[
            V::output("x", &[2, 2], 1, None, "", &[]).state_by_columns(),
            V::output("y", &[1], 5, None, "", &[]),
            // Declared in the other order: the derivatives' order is the states'.
            V::output("dy", &[1], 6, None, "", &[]).derivative_named("y", &[]),
            V::output("dx", &[2, 2], 7, None, "", &[]).derivative_named("x", &[]),
        ];
        const N: usize = state_count(TABLE);
        assert_eq!(states::<N>(TABLE), [("y", 0), ("x", 0), ("x", 2), ("x", 1), ("x", 3)]);
    }

    #[test]
    fn the_platforms_states_are_the_simulations_layout() {
        let s = crate::models::platform::variables::STATES;
        assert_eq!(s.len(), SIMULATION_DIM);
        // The special form's r, v, e_b, e_b': e_b is column b of R.
        for c in 0..3 {
            assert_eq!(index(s, "r", c), c);
            assert_eq!(index(s, "v", c), 3 + c);
            for b in 0..3 {
                assert_eq!(index(s, "R", 3 * c + b), 6 + 3 * b + c, "R[{},{}]", c + 1, b + 1);
                assert_eq!(index(s, "der(R)", 3 * c + b), 15 + 3 * b + c);
            }
        }
        assert_eq!(index(s, "work.F", 0), quadrature::WORK_F);
        assert_eq!(index(s, "work.dissipated", 0), quadrature::WORK_DISSIPATED);
        assert_eq!(index(s, "work.electric", 0), quadrature::WORK_ELECTRIC);
        assert_eq!(index(s, "work.hydraulic", 0), quadrature::WORK_HYDRAULIC);
        assert_eq!(index(s, "work.compression", 0), quadrature::WORK_COMPRESSION);
        for k in 0..6 {
            assert_eq!(index(s, "I", k), CURRENTS + k);
            assert_eq!(index(s, "pA", k), hydraulic::PA + k);
            assert_eq!(index(s, "pB", k), hydraulic::PB + k);
            assert_eq!(index(s, "spool", k), hydraulic::SPOOL + k);
            assert_eq!(index(s, "der(spool)", k), hydraulic::SPOOL_RATE + k);
        }
        assert_eq!(STATE_DIM, 24);
    }

    #[test]
    fn the_cueing_states_are_the_washouts_layout() {
        use crate::physics::cueing::washout::{STATE_DIM, layout::*};
        let s = crate::models::cueing::variables::STATES;
        assert_eq!(s.len(), crate::models::cueing::CONTINUOUS_STATES);
        // The perception's lags follow the washout's, in PerceptionStates::to_array's order.
        for (group, at, count) in [
            ("perception.vehicle.otolith", STATE_DIM, 6),
            ("perception.vehicle.canal", STATE_DIM + 6, 9),
            ("perception.simulator.otolith", STATE_DIM + 15, 6),
            ("perception.simulator.canal", STATE_DIM + 21, 9),
            ("washout.q", TRANSLATION_Q, 3),
            ("washout.r", HEAD_R, 3),
            ("washout.v", HEAD_V, 3),
            ("washout.fl", TILT_F, 2),
            ("der(washout.fl)", TILT_FDOT, 2),
            ("washout.tilt", TILT_ANGLES, 2),
            ("washout.z", ROTATION_Q, 3),
            ("washout.angles", ROTATION_ANGLES, 3),
        ] {
            for k in 0..count {
                assert_eq!(index(s, group, k), at + k, "{group}[{k}]");
            }
        }
    }
}
