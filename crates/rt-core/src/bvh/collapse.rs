//! The second step of the build: the binary tree collapsed into an 8-wide
//! one, as Embree's BVH8 (Wald, Benthin and Boulos, "Getting Rid of
//! Packets", 2008). Each node opens its widest inner child (by surface
//! area) until it has eight children, which keeps the SAH tree's splits.
//!
//! Nodes are listed depth first, each before its subtrees, in slot order.
//! A large node's children are collapsed on several threads, each into a
//! list of its own (its nodes numbered from 0), and the lists are appended
//! in slot order with their node numbers raised by where they land: the
//! same list, node for node, as collapsing on one thread gives (tested).

use std::ops::Range;

use rayon::prelude::*;

use super::build::BuildNode;
use super::leaf::LANES;
use super::node::{Child, Node, WIDTH};
use crate::math::real::to_f64;

/// Nodes over more items than this collapse their children on several
/// threads (where there are several); smaller ones on the calling thread.
const PARALLEL_ITEMS: u32 = 32 * 1024;

/// What collapsing a subtree produced: its child entry, the 8-wide nodes on
/// its longest path down, its traversal stack bound (see
/// [`super::Bvh::stack_bound`]), its share of the SAH cost
/// ([`super::BvhStats::sah_cost`]) before dividing by the root's area, and
/// how many leaves it has.
pub(super) struct Collapsed {
    pub child: Child,
    pub depth: usize,
    pub stack: usize,
    pub cost: f64,
    pub leaves: usize,
}

/// The leaves' blocks of items, in item order (each leaf's blocks are
/// consecutive), and how a leaf's child entry is made:
/// `leaf(block, first, count)` for the leaf over items `first..first +
/// count` whose blocks start at `blocks[block]`.
pub(super) struct Leaves<'a, F> {
    pub blocks: &'a [Range<usize>],
    pub leaf: F,
}

impl<F: Fn(u32, u32, u32) -> Child + Sync> Leaves<'_, F> {
    /// The first block at or after item `item`.
    fn block_of(&self, item: u32) -> u32 {
        self.blocks.partition_point(|b| b.start < item as usize) as u32
    }
}

/// Collapses the tree with root `node`, whose children are in `arena`,
/// into `nodes` (empty; the root's node, if it is not a leaf, first).
pub(super) fn collapse(
    node: &BuildNode,
    arena: &[[BuildNode; 2]],
    nodes: &mut Vec<Node>,
    leaves: &Leaves<impl Fn(u32, u32, u32) -> Child + Sync>,
) -> Collapsed {
    debug_assert!(nodes.is_empty());
    collapse_node(node, arena, nodes, &mut 0, leaves)
}

/// Collapses `node`, whose children are in `arena` (a
/// [`BuildNode::Subtree`] brings its own), into `nodes` (appending); its
/// first leaf's blocks start at `blocks[*block]`, and `*block` moves past
/// its last leaf's.
fn collapse_node(
    node: &BuildNode,
    arena: &[[BuildNode; 2]],
    nodes: &mut Vec<Node>,
    block: &mut u32,
    leaves: &Leaves<impl Fn(u32, u32, u32) -> Child + Sync>,
) -> Collapsed {
    let area = |n: &BuildNode| to_f64(n.bounds().surface_area());
    let (node, arena) = node.resolve(arena);
    let BuildNode::Inner { children, .. } = node else {
        let BuildNode::Leaf { first, count, .. } = node else { unreachable!() };
        let child = (leaves.leaf)(*block, *first, *count);
        *block += count.div_ceil(LANES as u32);
        let cost = area(node) * f64::from(child.lanes.tests());
        return Collapsed { child, depth: 0, stack: 0, cost, leaves: 1 };
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
    let (mut depth, mut stack, mut leaf_count) = (0, 0, 0);
    let mut put = |nodes: &mut Vec<Node>, slot: usize, c: &BuildNode, below: Collapsed| {
        nodes[index].set(slot, c.bounds(), below.child);
        depth = depth.max(below.depth);
        stack = stack.max(below.stack);
        cost += below.cost;
        leaf_count += below.leaves;
    };
    let (first, count) = node.items();
    if count > PARALLEL_ITEMS && rayon::current_num_threads() > 1 {
        // Each child into a list of its own, its first block found from its first item.
        let parts: Vec<(Vec<Node>, Collapsed)> = open
            .par_iter()
            .map(|&(c, arena)| {
                let mut own = Vec::new();
                let below = collapse_node(c, arena, &mut own, &mut leaves.block_of(c.items().0), leaves);
                (own, below)
            })
            .collect();
        for (slot, ((own, mut below), &(c, _))) in parts.into_iter().zip(open).enumerate() {
            let offset = nodes.len() as u32;
            if !below.child.is_leaf() {
                below.child.index += offset;
            }
            nodes.par_extend(own.into_par_iter().map(|n| n.renumbered(offset)));
            put(nodes, slot, c, below);
        }
        *block = leaves.block_of(first + count);
    } else {
        for (slot, &(c, arena)) in open.iter().enumerate() {
            let below = collapse_node(c, arena, nodes, block, leaves);
            put(nodes, slot, c, below);
        }
    }
    Collapsed {
        child: Child::node(index as u32),
        depth: depth + 1,
        stack: stack + open.len() - 1,
        cost,
        leaves: leaf_count,
    }
}
