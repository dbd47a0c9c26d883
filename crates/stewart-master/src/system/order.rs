//! The order in which a Gauss-Seidel step sets the components' inputs.

use super::Component;

/// What the order needs of a component: its name and the components its connected inputs come
/// from.
pub(super) struct Reader<'a> {
    pub name: &'a str,
    pub sources: Vec<usize>,
}

impl<'a> Reader<'a> {
    pub fn of(component: &'a Component) -> Self {
        Reader { name: &component.name, sources: component.inputs.iter().map(|&(_, from, _)| from).collect() }
    }
}

/// The Gauss-Seidel order: a component gets its inputs once every component it reads from
/// either has no direct feed-through (its outputs are known at the communication point) or has
/// had its inputs already. A cycle of feed-through components (an algebraic loop) is refused.
pub(super) fn gauss_seidel_order(components: &[Reader<'_>], feedthrough: &[bool]) -> Result<Vec<usize>, String> {
    let mut order = vec![];
    let mut done = vec![false; components.len()];
    while order.len() < components.len() {
        let ready = (0..components.len()).find(|&k| {
            !done[k] && components[k].sources.iter().all(|&from| !feedthrough[from] || done[from] || from == k)
        });
        match ready {
            Some(k) if feedthrough[k] && components[k].sources.contains(&k) => {
                return Err(format!("{} feeds its own input through directly: an algebraic loop", components[k].name));
            }
            Some(k) => {
                done[k] = true;
                order.push(k);
            }
            None => {
                let rest: Vec<&str> = (0..components.len()).filter(|&k| !done[k]).map(|k| components[k].name).collect();
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

#[cfg(test)]
mod tests {
    use super::*;

    fn reader<'a>(name: &'a str, sources: &[usize]) -> Reader<'a> {
        Reader { name, sources: sources.to_vec() }
    }

    /// The closed loop: the platform (no feed-through) reads the controller, whose forces depend
    /// directly on the legs it reads from the platform: the controller's inputs first.
    #[test]
    fn a_component_comes_after_the_feed_through_components_it_reads() {
        let system = [reader("platform", &[1]), reader("controller", &[0])];
        assert_eq!(gauss_seidel_order(&system, &[false, true]), Ok(vec![1, 0]));
        // Without feed-through anywhere, element order.
        assert_eq!(gauss_seidel_order(&system, &[false, false]), Ok(vec![0, 1]));
        // The motion system: cueing -> controller -> platform -> controller.
        let chain = [reader("platform", &[2]), reader("cueing", &[]), reader("controller", &[1, 0])];
        assert_eq!(gauss_seidel_order(&chain, &[false, false, true]), Ok(vec![1, 2, 0]));
    }

    #[test]
    fn an_algebraic_loop_is_refused_by_name() {
        let two = [reader("a", &[1]), reader("b", &[0])];
        let loop_of_two = gauss_seidel_order(&two, &[true, true]).unwrap_err();
        assert!(loop_of_two.contains("the components a, b form an algebraic loop"), "{loop_of_two}");
        let own = [reader("a", &[0])];
        let own_loop = gauss_seidel_order(&own, &[true]).unwrap_err();
        assert!(own_loop.contains("a feeds its own input through directly"), "{own_loop}");
        // A component that reads itself without feed-through is no loop.
        assert_eq!(gauss_seidel_order(&own, &[false]), Ok(vec![0]));
    }
}
