//! The second step of the build: the binary tree collapsed into an 8-wide
//! one, as Embree's BVH8 (Wald, Benthin and Boulos, "Getting Rid of
//! Packets", 2008). Each node opens its widest inner child (by surface
//! area) until it has eight children, which keeps the SAH tree's splits.

use super::build::BuildNode;
use super::node::{Child, Node, WIDTH};
use crate::math::real::to_f64;

/// What collapsing a subtree produced: its child entry, the 8-wide nodes on
/// its longest path down, its traversal stack bound (see
/// [`super::Bvh::stack_bound`]), and its share of the SAH cost
/// ([`super::BvhStats::sah_cost`]) before dividing by the root's area.
pub(super) struct Collapsed {
    pub child: Child,
    pub depth: usize,
    pub stack: usize,
    pub cost: f64,
}

/// Collapses `node`, whose children are in `arena` (a
/// [`BuildNode::Subtree`] brings its own), into `nodes` (appending);
/// `leaf(first, count)` makes the child entry of the leaf over items
/// `first..first + count`.
pub(super) fn collapse(
    node: &BuildNode,
    arena: &[[BuildNode; 2]],
    nodes: &mut Vec<Node>,
    leaf: &mut impl FnMut(u32, u32) -> Child,
) -> Collapsed {
    let area = |n: &BuildNode| to_f64(n.bounds().surface_area());
    let (node, arena) = node.resolve(arena);
    let BuildNode::Inner { children, .. } = node else {
        let BuildNode::Leaf { first, count, .. } = node else { unreachable!() };
        let child = leaf(*first, *count);
        let cost = area(node) * f64::from(child.lanes.tests());
        return Collapsed { child, depth: 0, stack: 0, cost };
    };
    // The children it opens to, each with the arena of its own children,
    // on the stack: `open[..len]`.
    fn pair(children: u32, arena: &[[BuildNode; 2]]) -> [(&BuildNode, &[[BuildNode; 2]]); 2] {
        let [a, b] = &arena[children as usize];
        [a.resolve(arena), b.resolve(arena)]
    }
    let mut open: [(&BuildNode, &[[BuildNode; 2]]); WIDTH] = [(node, arena); WIDTH];
    open[..2].copy_from_slice(&pair(*children, arena));
    let mut len = 2;
    while len < WIDTH {
        let widest = open[..len]
            .iter()
            .enumerate()
            .filter(|(_, c)| matches!(c.0, BuildNode::Inner { .. }))
            .max_by(|a, b| area(a.1.0).total_cmp(&area(b.1.0)));
        let Some((slot, (BuildNode::Inner { children, .. }, arena))) = widest.map(|(slot, c)| (slot, *c))
        else {
            break;
        };
        open.copy_within(slot + 1..len, slot + 2);
        open[slot..slot + 2].copy_from_slice(&pair(*children, arena));
        len += 1;
    }
    let open = &open[..len];
    let index = nodes.len();
    nodes.push(Node::EMPTY);
    // A node visit costs TRAVERSAL_COST per unit of its area.
    let mut cost = area(node) * to_f64(super::build::TRAVERSAL_COST);
    let (mut depth, mut stack) = (0, 0);
    for (slot, &(c, arena)) in open.iter().enumerate() {
        let below = collapse(c, arena, nodes, leaf);
        nodes[index].set(slot, c.bounds(), below.child);
        depth = depth.max(below.depth);
        stack = stack.max(below.stack);
        cost += below.cost;
    }
    Collapsed { child: Child::node(index as u32), depth: depth + 1, stack: stack + open.len() - 1, cost }
}
