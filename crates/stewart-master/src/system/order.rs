//! The order in which a Gauss-Seidel step sets the components' inputs.

use super::Component;

/// The Gauss-Seidel order: a component gets its inputs once every component it reads from
/// either has no direct feed-through (its outputs are known at the communication point) or has
/// had its inputs already. A cycle of feed-through components (an algebraic loop) is refused.
pub(super) fn gauss_seidel_order(components: &[Component], feedthrough: &[bool]) -> Result<Vec<usize>, String> {
    let mut order = vec![];
    let mut done = vec![false; components.len()];
    while order.len() < components.len() {
        let ready = (0..components.len()).find(|&k| {
            !done[k] && components[k].inputs.iter().all(|&(_, from, _)| !feedthrough[from] || done[from] || from == k)
        });
        match ready {
            Some(k) if feedthrough[k] && components[k].inputs.iter().any(|&(_, from, _)| from == k) => {
                return Err(format!("{} feeds its own input through directly: an algebraic loop", components[k].name));
            }
            Some(k) => {
                done[k] = true;
                order.push(k);
            }
            None => {
                let rest: Vec<&str> =
                    (0..components.len()).filter(|&k| !done[k]).map(|k| components[k].name.as_str()).collect();
                return Err(format!(
                    "the components {} form an algebraic loop (outputs that depend directly on inputs, in a cycle): \
                     a fixed-step master cannot order them",
                    rest.join(", ")
                ));
            }
        }
    }
    Ok(order)
}
