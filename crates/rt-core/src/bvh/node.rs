//! A node of the 8-wide tree: the boxes of up to eight children side by
//! side, so that one slab test covers them all, and what each child is.

use super::leaf::Lanes;
use crate::geometry::aabb::Aabb;
use crate::math::real::Real;

/// Children per node.
pub(super) const WIDTH: usize = 8;

/// A child slot of a [`Node`]: an inner node (`lanes` 0), or the leaf
/// whose blocks start at `leaves[index]`, with its [`Lanes`] (which also
/// tell how many blocks it has).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Child {
    pub index: u32,
    pub lanes: Lanes,
}

impl Child {
    /// The inner node `nodes[index]`.
    pub const fn node(index: u32) -> Self {
        Self { index, lanes: Lanes(0) }
    }
    pub fn is_leaf(self) -> bool {
        self.lanes.0 != 0
    }
}

/// An 8-wide node: the boxes of its children, stored axis by axis
/// (`bounds[min or max][axis][slot]`) so that one slab test covers all
/// eight. Unused slots have the empty box (min = +∞, max = −∞), which no ray
/// enters.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub(super) struct Node {
    /// `bounds[0]` are the minima, `bounds[1]` the maxima.
    pub bounds: [[[Real; WIDTH]; 3]; 2],
    pub children: [Child; WIDTH],
}

impl Node {
    /// A node with every slot empty.
    pub const EMPTY: Node = Node {
        bounds: [[[Real::INFINITY; WIDTH]; 3], [[Real::NEG_INFINITY; WIDTH]; 3]],
        children: [Child::node(0); WIDTH],
    };

    /// This node of a list of nodes of its own, with the list moved to
    /// `offset` in another: its inner children's numbers raised by `offset`.
    /// No child is node 0 of its list (that is the list's root, listed
    /// before all of its descendants), so an empty slot, which holds node 0,
    /// keeps it.
    pub fn renumbered(mut self, offset: u32) -> Node {
        for child in &mut self.children {
            if !child.is_leaf() && child.index != 0 {
                child.index += offset;
            }
        }
        self
    }

    /// Puts `child` with `bounds` into `slot`.
    pub fn set(&mut self, slot: usize, bounds: Aabb, child: Child) {
        for axis in 0..3 {
            self.bounds[0][axis][slot] = bounds.min()[axis];
            self.bounds[1][axis][slot] = bounds.max()[axis];
        }
        self.children[slot] = child;
    }
}
