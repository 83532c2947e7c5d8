//! A built hierarchy as plain arrays of numbers and back: what a scene
//! cache stores instead of building the tree again.
//!
//! The arrays are the tree's own storage, node by node and leaf by leaf
//! ([`Bvh::arrays`]); taking them back ([`Bvh::from_arrays`]) checks every
//! index before the tree is used, since the traversal trusts them: each
//! inner child comes after its parent (so the tree has no cycle and every
//! walk ends), each leaf's blocks are in the leaf list, each lane names an
//! object there (a triangle lane a mesh triangle that exists), and the
//! traversal's stack bound is computed again from the tree, never read.

use thiserror::Error;

use super::leaf::{BLOCKS, Lanes, Leaf, lanes_of};
use super::node::{Child, Node, WIDTH};
use super::{Bvh, BvhStats};
use crate::geometry::aabb::Aabb;
use crate::geometry::object::Object;
use crate::geometry::primitive::Primitive;
use crate::math::real::Real;

/// Reals per node: `bounds[min or max][axis][slot]`.
pub const NODE_REALS: usize = 2 * 3 * WIDTH;
/// Indices per node: each slot's child index, then its lane masks.
pub const NODE_IDS: usize = 2 * WIDTH;

/// A hierarchy's storage as plain numbers (see the module documentation).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BvhArrays {
    /// 48 per node: the children's boxes, minima then maxima,
    /// axis by axis, slot by slot.
    pub node_bounds: Vec<Real>,
    /// 16 per node: for each slot its child index and lane masks
    /// (0 for an inner node).
    pub node_children: Vec<u32>,
    /// 36 per leaf block: the corners, `[corner][axis][lane]`.
    pub leaf_corners: Vec<Real>,
    /// 8 per leaf block: the lanes' objects, then their triangle indices.
    pub leaf_ids: Vec<u32>,
    /// Objects without bounds, tested on every query.
    pub unbounded: Vec<u32>,
    /// The box around every bounded object.
    pub bounds: Option<Aabb>,
    /// The build's surface-area-heuristic cost ([`BvhStats::sah_cost`]).
    pub sah_cost: f64,
}

/// Why arrays do not make a hierarchy over the given objects.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum BvhArraysError {
    /// An array's length is not a whole number of entries, or the node and
    /// leaf arrays disagree in count.
    #[error("BVH arrays of inconsistent lengths: {0}")]
    Lengths(String),
    /// A child slot names a node, a leaf or an object that is not there.
    #[error("BVH node {node}, slot {slot}: {reason}")]
    Child {
        /// The node.
        node: usize,
        /// The slot in it.
        slot: usize,
        /// What is wrong.
        reason: String,
    },
    /// An object without bounds that is not in the scene.
    #[error("BVH: unbounded object {0} is not in the scene")]
    Unbounded(u32),
}

impl Bvh {
    /// The tree's storage as plain numbers ([`BvhArrays`]); borrow them
    /// back with [`BvhArrays::as_ref`].
    pub fn arrays(&self) -> BvhArrays {
        let mut a = BvhArrays {
            node_bounds: Vec::with_capacity(self.nodes.len() * NODE_REALS),
            node_children: Vec::with_capacity(self.nodes.len() * NODE_IDS),
            leaf_corners: Vec::with_capacity(self.leaves.len() * Leaf::FLAT_REALS),
            leaf_ids: Vec::with_capacity(self.leaves.len() * Leaf::FLAT_IDS),
            unbounded: self.unbounded.clone(),
            bounds: self.bounds,
            sah_cost: self.stats.sah_cost,
        };
        for node in &self.nodes {
            a.node_bounds.extend(node.bounds.iter().flatten().flatten());
            a.node_children.extend(node.children.iter().flat_map(|c| [c.index, c.lanes.0]));
        }
        for leaf in &self.leaves {
            leaf.flatten(&mut a.leaf_corners, &mut a.leaf_ids);
        }
        a
    }

    /// The tree [`Bvh::arrays`] gave, over `objects` (the scene's, in the
    /// same order), every index checked (see the module documentation).
    /// The statistics' node, block and byte counts come from the arrays.
    pub fn from_arrays(a: BvhArraysRef<'_>, objects: &[Object]) -> Result<Self, BvhArraysError> {
        let lengths = |what: String| Err(BvhArraysError::Lengths(what));
        if !a.node_bounds.len().is_multiple_of(NODE_REALS)
            || a.node_children.len() != a.node_bounds.len() / NODE_REALS * NODE_IDS
        {
            return lengths(format!(
                "{} node reals and {} node indices",
                a.node_bounds.len(),
                a.node_children.len()
            ));
        }
        if !a.leaf_corners.len().is_multiple_of(Leaf::FLAT_REALS)
            || a.leaf_ids.len() != a.leaf_corners.len() / Leaf::FLAT_REALS * Leaf::FLAT_IDS
        {
            return lengths(format!(
                "{} leaf reals and {} leaf indices",
                a.leaf_corners.len(),
                a.leaf_ids.len()
            ));
        }
        if let Some(&o) = a.unbounded.iter().find(|&&o| o as usize >= objects.len()) {
            return Err(BvhArraysError::Unbounded(o));
        }
        let mut leaves: Vec<Leaf> = a
            .leaf_corners
            .chunks_exact(Leaf::FLAT_REALS)
            .zip(a.leaf_ids.chunks_exact(Leaf::FLAT_IDS))
            .map(|(reals, ids)| Leaf::from_flat(reals, ids))
            .collect();
        let mut nodes = Vec::with_capacity(a.node_bounds.len() / NODE_REALS);
        for (reals, ids) in a.node_bounds.chunks_exact(NODE_REALS).zip(a.node_children.chunks_exact(NODE_IDS))
        {
            let mut node = Node::EMPTY;
            for (to, from) in node.bounds.iter_mut().flatten().flatten().zip(reals) {
                *to = *from;
            }
            for (slot, c) in ids.chunks_exact(2).enumerate() {
                node.children[slot] = Child { index: c[0], lanes: Lanes(c[1]) };
            }
            nodes.push(node);
        }
        if nodes.is_empty() && !leaves.is_empty() {
            return lengths(format!("{} leaf blocks but no node", leaves.len()));
        }
        // Children come after their parents: from the last node back, each
        // node's stack bound and depth from its children's (as the build's
        // collapse computes them).
        let mut stack = vec![0usize; nodes.len()];
        let mut depth = vec![0usize; nodes.len()];
        let mut leaf_count = 0;
        let mut primitives = 0;
        for n in (0..nodes.len()).rev() {
            let node = &nodes[n];
            let (mut used, mut below_stack, mut below_depth) = (0, 0, 0);
            for slot in 0..WIDTH {
                let child = node.children[slot];
                let fail = |reason: String| Err(BvhArraysError::Child { node: n, slot, reason });
                if child.is_leaf() {
                    let blocks = child.lanes.blocks();
                    let end = child.index as usize + blocks;
                    if blocks > BLOCKS || end > leaves.len() {
                        return fail(format!(
                            "a leaf of {blocks} blocks at {} (the tree has {})",
                            child.index,
                            leaves.len()
                        ));
                    }
                    for (b, leaf) in leaves[child.index as usize..end].iter().enumerate() {
                        let lanes = child.lanes.block(b);
                        for lane in lanes_of(lanes.triangles()) {
                            let (o, i) = (leaf.object(lane), leaf.index(lane));
                            match objects.get(o as usize).map(|o| &o.primitive) {
                                Some(Primitive::Mesh(m)) if (i as usize) < m.triangle_count() => {}
                                _ => {
                                    return fail(format!(
                                        "lane {lane} names triangle {i} of object {o}: none"
                                    ));
                                }
                            }
                        }
                        for lane in lanes_of(lanes.objects()) {
                            if leaf.object(lane) as usize >= objects.len() {
                                return fail(format!("lane {lane} names object {}: none", leaf.object(lane)));
                            }
                        }
                        primitives += (lanes.triangles() | lanes.objects()).count_ones() as usize;
                    }
                    leaf_count += 1;
                    used += 1;
                } else if (child.index as usize) > n && (child.index as usize) < nodes.len() {
                    below_stack = below_stack.max(stack[child.index as usize]);
                    below_depth = below_depth.max(depth[child.index as usize]);
                    used += 1;
                } else if child == Child::node(0) && is_empty_slot(node, slot) {
                    // An unused slot: its empty box is never entered.
                } else {
                    return fail(format!("inner child {} (children follow their parent)", child.index));
                }
            }
            stack[n] = below_stack + used.max(1) - 1;
            depth[n] = below_depth + 1;
        }
        // The block numbers of whole-object lanes are worked out again, not
        // trusted.
        let object_blocks = super::object_block::attach(&mut leaves, objects);
        let stats = BvhStats {
            primitives,
            nodes: nodes.len(),
            width: WIDTH,
            leaves: leaf_count,
            leaf_blocks: leaves.len(),
            depth: depth.first().copied().unwrap_or(0),
            bytes: nodes.len() * size_of::<Node>()
                + leaves.len() * size_of::<Leaf>()
                + object_blocks.len() * size_of::<super::object_block::ObjectBlock>(),
            sah_cost: a.sah_cost,
            build_time: std::time::Duration::ZERO,
            build_steps: super::BuildSteps::default(),
        };
        Ok(Self {
            nodes: super::huge_pages::moved(nodes),
            leaves: super::huge_pages::moved(leaves),
            object_blocks,
            stack_bound: stack.first().copied().unwrap_or(0),
            unbounded: a.unbounded.to_vec(),
            triangles: super::has_meshes(objects),
            bounds: a.bounds,
            stats,
        })
    }
}

impl BvhArrays {
    /// The arrays borrowed, for [`Bvh::from_arrays`].
    pub fn as_ref(&self) -> BvhArraysRef<'_> {
        BvhArraysRef {
            node_bounds: &self.node_bounds,
            node_children: &self.node_children,
            leaf_corners: &self.leaf_corners,
            leaf_ids: &self.leaf_ids,
            unbounded: &self.unbounded,
            bounds: self.bounds,
            sah_cost: self.sah_cost,
        }
    }
}

/// [`BvhArrays`] borrowed (from a mapped file, say).
#[derive(Clone, Copy, Debug)]
pub struct BvhArraysRef<'a> {
    /// See [`BvhArrays::node_bounds`].
    pub node_bounds: &'a [Real],
    /// See [`BvhArrays::node_children`].
    pub node_children: &'a [u32],
    /// See [`BvhArrays::leaf_corners`].
    pub leaf_corners: &'a [Real],
    /// See [`BvhArrays::leaf_ids`].
    pub leaf_ids: &'a [u32],
    /// See [`BvhArrays::unbounded`].
    pub unbounded: &'a [u32],
    /// See [`BvhArrays::bounds`].
    pub bounds: Option<Aabb>,
    /// The build's surface-area-heuristic cost ([`BvhStats::sah_cost`]).
    pub sah_cost: f64,
}

/// Whether `slot` of `node` is an unused one: the empty box (+∞ minima,
/// −∞ maxima), which no ray enters.
fn is_empty_slot(node: &Node, slot: usize) -> bool {
    (0..3).all(|axis| {
        node.bounds[0][axis][slot] == Real::INFINITY && node.bounds[1][axis][slot] == Real::NEG_INFINITY
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    use super::super::BuildSteps;
    use crate::geometry::sphere::Sphere;
    use crate::math::ray::{Interval, Ray};
    use crate::math::real::Vec3;
    use crate::testing::test_support::grid_mesh;

    /// A 40×40 grid mesh (3200 triangles, a tree several levels deep) and a sphere.
    fn objects() -> Vec<Object> {
        let mesh = grid_mesh(40, |i, j| Vec3::new(i as Real, ((i * j) % 7) as Real * 0.1, j as Real));
        let sphere = Sphere::new(Vec3::new(5.0, 3.0, 5.0), 1.0).unwrap();
        vec![
            Object { primitive: Primitive::Mesh(mesh), material: 0 },
            Object { primitive: Primitive::Sphere(sphere), material: 0 },
        ]
    }

    #[test]
    fn a_tree_from_its_arrays_answers_as_the_built_one_with_the_same_stack_bound() {
        let objects = objects();
        let built = Bvh::build(&objects);
        let arrays = built.arrays();
        let back = Bvh::from_arrays(arrays.as_ref(), &objects).unwrap();
        assert_eq!(back.stack_bound, built.stack_bound);
        let (a, b) = (back.stats(), built.stats());
        // Read back, not built: no build time, no steps.
        assert_eq!((a.build_time, a.build_steps), (Duration::ZERO, BuildSteps::default()));
        assert!(b.build_steps.binary_tree > Duration::ZERO);
        assert_eq!(
            (a.nodes, a.leaves, a.leaf_blocks, a.depth, a.primitives),
            (b.nodes, b.leaves, b.leaf_blocks, b.depth, b.primitives)
        );
        for k in 0..50 {
            let o = Vec3::new(k as Real * 0.8, 10.0, 20.0 - k as Real * 0.3);
            let ray = Ray::new(o, Vec3::new(0.1, -1.0, 0.05 * k as Real - 1.0));
            let range = Interval::new(0.0, Real::INFINITY);
            let methods = Default::default();
            assert_eq!(
                back.closest_hit(&objects, &ray, range, methods),
                built.closest_hit(&objects, &ray, range, methods)
            );
        }
    }

    /// `arrays` with `change` applied, taken back over `objects`.
    fn changed(change: impl Fn(&mut BvhArrays)) -> Result<Bvh, BvhArraysError> {
        let objects = objects();
        let mut arrays = Bvh::build(&objects).arrays();
        change(&mut arrays);
        Bvh::from_arrays(arrays.as_ref(), &objects)
    }

    #[test]
    fn a_child_pointing_back_up_the_tree_is_refused() {
        // Slot 0 of the last node made an inner child pointing at the root: a cycle.
        let e = changed(|a| {
            let last = a.node_children.len() - NODE_IDS;
            a.node_children[last] = 0;
            a.node_children[last + 1] = 0;
            let reals = a.node_bounds.len() - NODE_REALS;
            a.node_bounds[reals] = 0.0;
        })
        .unwrap_err();
        assert!(matches!(e, BvhArraysError::Child { .. }), "{e}");
    }

    #[test]
    fn indices_out_of_range_are_refused() {
        let leaf_child = |a: &BvhArrays| {
            (0..a.node_children.len()).step_by(2).find(|&i| a.node_children[i + 1] != 0).unwrap()
        };
        // A leaf beyond the leaf list.
        let e = changed(|a| {
            let i = leaf_child(a);
            a.node_children[i] = (a.leaf_ids.len() / Leaf::FLAT_IDS) as u32;
        });
        assert!(matches!(e, Err(BvhArraysError::Child { .. })), "{e:?}");
        // A lane naming an object that is not there, and a triangle that is not.
        let e = changed(|a| a.leaf_ids[0] = 7);
        assert!(matches!(e, Err(BvhArraysError::Child { .. })), "{e:?}");
        let e = changed(|a| a.leaf_ids[LANES_IN_IDS] = 1_000_000);
        assert!(matches!(e, Err(BvhArraysError::Child { .. })), "{e:?}");
        // An inner child beyond the node list, arrays cut short, an unbounded object that is not there.
        let e = changed(|a| {
            let i = (0..a.node_children.len())
                .step_by(2)
                .find(|&i| a.node_children[i + 1] == 0 && a.node_children[i] != 0)
                .unwrap();
            a.node_children[i] = u32::MAX;
        });
        assert!(matches!(e, Err(BvhArraysError::Child { .. })), "{e:?}");
        let e = changed(|a| {
            a.leaf_ids.pop();
        });
        assert!(matches!(e, Err(BvhArraysError::Lengths(_))), "{e:?}");
        let e = changed(|a| a.unbounded.push(9));
        assert_eq!(e.unwrap_err(), BvhArraysError::Unbounded(9));
    }

    /// Where a leaf's triangle indices start in its ids.
    const LANES_IN_IDS: usize = Leaf::FLAT_IDS / 2;
}
