//! Where the accuracy plot's point labels go, so that none prints over
//! another: points that share a place (every exact result lies on the
//! plot's floor) would otherwise stack their labels on one spot.
//!
//! Greedy placement, as map labelling does in its simplest form: labels
//! are placed one by one, left to right; each takes the first of a fixed
//! list of places around its point (above right, below right, above left,
//! below left, then ever further above and below on the right) whose box
//! overlaps no label already placed. A label pushed more than a line away
//! from its point gets a leader line back to it ([`Placed::leader`]).

/// A label's box in pixels, relative to its point: the top-left corner's
/// offset and the size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Placed {
    /// Offset of the label's top-left corner from its point.
    pub offset: (i32, i32),
    /// Width and height of the label.
    pub size: (u32, u32),
    /// Whether the label is far enough from its point to need a line to it.
    pub leader: bool,
}

/// Gap between a point and its label, pixels.
const GAP: i32 = 5;

/// Farthest a label is pushed, in lines above or below its point.
const MAX_LINES: i32 = 12;

/// The places tried for a label of `size` beside its point, nearest first.
fn candidates((w, h): (u32, u32)) -> Vec<(i32, i32)> {
    let (w, h) = (w as i32, h as i32);
    let mut out = vec![(GAP, -h - GAP / 2), (GAP, GAP / 2), (-w - GAP, -h - GAP / 2), (-w - GAP, GAP / 2)];
    for line in 1..=MAX_LINES {
        out.push((GAP, -h - GAP / 2 - line * h));
        out.push((GAP, GAP / 2 + line * h));
    }
    out
}

/// Whether two boxes (top-left corner, size) overlap.
fn overlaps(a: (i32, i32), (aw, ah): (u32, u32), b: (i32, i32), (bw, bh): (u32, u32)) -> bool {
    a.0 < b.0 + bw as i32 && b.0 < a.0 + aw as i32 && a.1 < b.1 + bh as i32 && b.1 < a.1 + ah as i32
}

/// Places a label of size `sizes[i]` beside each point `points[i]` (pixel
/// coordinates), in the module's order: one [`Placed`] per point, in the
/// points' order. Where every place is taken the label goes to its
/// farthest one (overlap there is accepted rather than lose a label).
pub fn place(points: &[(i32, i32)], sizes: &[(u32, u32)]) -> Vec<Placed> {
    assert_eq!(points.len(), sizes.len(), "a size for every label");
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by_key(|&i| (points[i].0, points[i].1));
    let mut placed: Vec<Option<Placed>> = vec![None; points.len()];
    let mut taken: Vec<((i32, i32), (u32, u32))> = Vec::new();
    for i in order {
        let (p, size) = (points[i], sizes[i]);
        let places = candidates(size);
        let offset = places
            .iter()
            .copied()
            .find(|&(dx, dy)| {
                let corner = (p.0 + dx, p.1 + dy);
                taken.iter().all(|&(c, s)| !overlaps(corner, size, c, s))
            })
            .unwrap_or(*places.last().expect("places"));
        taken.push(((p.0 + offset.0, p.1 + offset.1), size));
        let leader = offset.1 < -(size.1 as i32) - GAP || offset.1 > size.1 as i32;
        placed[i] = Some(Placed { offset, size, leader });
    }
    placed.into_iter().map(|p| p.expect("every label placed")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn corners(points: &[(i32, i32)], placed: &[Placed]) -> Vec<((i32, i32), (u32, u32))> {
        points.iter().zip(placed).map(|(p, l)| ((p.0 + l.offset.0, p.1 + l.offset.1), l.size)).collect()
    }

    #[test]
    fn labels_of_points_on_one_spot_do_not_overlap_and_far_ones_get_a_leader() {
        // Six points where the floor gathers them, two apart in x, and one far away.
        let points = [(100, 400), (102, 400), (104, 400), (100, 400), (101, 400), (103, 400), (600, 50)];
        let sizes = [(90, 14); 7];
        let placed = place(&points, &sizes);
        let boxes = corners(&points, &placed);
        for (i, a) in boxes.iter().enumerate() {
            for b in &boxes[i + 1..] {
                assert!(!overlaps(a.0, a.1, b.0, b.1), "{a:?} overlaps {b:?}");
            }
        }
        assert!(placed.iter().any(|p| p.leader), "{placed:?}");
        // A lone point keeps the first place, above right, with no leader.
        assert_eq!(placed[6], Placed { offset: (GAP, -14 - GAP / 2), size: (90, 14), leader: false });
    }

    #[test]
    fn labels_that_do_not_collide_stay_beside_their_points() {
        let points = [(10, 10), (300, 10), (10, 300)];
        let placed = place(&points, &[(50, 12); 3]);
        assert!(placed.iter().all(|p| p.offset == (GAP, -12 - GAP / 2) && !p.leader), "{placed:?}");
    }

    #[test]
    fn boxes_overlap_only_when_they_share_area() {
        assert!(overlaps((0, 0), (10, 10), (5, 5), (10, 10)));
        assert!(!overlaps((0, 0), (10, 10), (10, 0), (10, 10)));
        assert!(!overlaps((0, 0), (10, 10), (0, 10), (10, 10)));
    }
}
