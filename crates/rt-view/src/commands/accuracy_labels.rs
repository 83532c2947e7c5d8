//! Where the accuracy plot's point labels go, so that none prints over
//! another: points that share a place (every exact result lies on the
//! plot's floor) would otherwise stack their labels on one spot.
//!
//! Greedy placement, as map labelling does in its simplest form: labels
//! are placed one by one, left to right; each takes the first of a fixed
//! list of places around its point (above right, below right, above left,
//! below left, then ever further above and below on the right) whose box
//! stays inside the area given (the chart's, clear of its axes' labels)
//! and overlaps no label already placed; of the four places right beside
//! the point, one that also covers no other point's dot goes first. A
//! label pushed more than a line away from its point gets a leader line
//! back to it ([`Placed::leader`]).

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

/// A box in pixels: its top-left corner and its size.
type Rect = ((i32, i32), (u32, u32));

/// Gap between a point and its label, pixels.
const GAP: i32 = 5;

/// Farthest a label is pushed, in lines above or below its point.
const MAX_LINES: i32 = 12;

/// How many of the places [`candidates`] lists are right beside the point
/// (the four corners around it).
const NEAR: usize = 4;

/// Half the side of the box a point's dot takes, pixels (the charts' dots
/// have a radius of 3 or 4).
const DOT: i32 = 5;

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
/// coordinates), in the module's order, inside `area` (pixel ranges in x
/// and y): one [`Placed`] per point, in the points'
/// order. Where every place inside the area is taken the label goes to the
/// first of them (overlap there is accepted rather than lose a label).
pub fn place(
    points: &[(i32, i32)],
    sizes: &[(u32, u32)],
    area: (std::ops::Range<i32>, std::ops::Range<i32>),
) -> Vec<Placed> {
    assert_eq!(points.len(), sizes.len(), "a size for every label");
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by_key(|&i| (points[i].0, points[i].1));
    let dots: Vec<Rect> =
        points.iter().map(|&(x, y)| ((x - DOT, y - DOT), (2 * DOT as u32, 2 * DOT as u32))).collect();
    let inside = |(x, y): (i32, i32), (w, h): (u32, u32)| {
        x >= area.0.start && x + w as i32 <= area.0.end && y >= area.1.start && y + h as i32 <= area.1.end
    };
    let mut placed: Vec<Option<Placed>> = vec![None; points.len()];
    let mut taken: Vec<Rect> = Vec::new();
    for i in order {
        let (p, size) = (points[i], sizes[i]);
        let places = candidates(size);
        let free = |obstacles: &[Rect], (dx, dy): (i32, i32)| {
            let corner = (p.0 + dx, p.1 + dy);
            inside(corner, size) && obstacles.iter().all(|&(c, s)| !overlaps(corner, size, c, s))
        };
        // Beside the point, clear of labels and dots; else anywhere on the
        // list clear of labels; else the first place inside the area.
        let offset = (places[..NEAR].iter().copied())
            .find(|&place| free(&taken, place) && free(&dots, place))
            .or_else(|| places.iter().copied().find(|&place| free(&taken, place)))
            .or_else(|| places.iter().copied().find(|&place| free(&[], place)))
            .unwrap_or(places[0]);
        taken.push(((p.0 + offset.0, p.1 + offset.1), size));
        let leader = offset.1 < -(size.1 as i32) - GAP || offset.1 > size.1 as i32;
        placed[i] = Some(Placed { offset, size, leader });
    }
    placed.into_iter().map(|p| p.expect("every label placed")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn corners(points: &[(i32, i32)], placed: &[Placed]) -> Vec<Rect> {
        points.iter().zip(placed).map(|(p, l)| ((p.0 + l.offset.0, p.1 + l.offset.1), l.size)).collect()
    }

    #[test]
    fn labels_of_points_on_one_spot_do_not_overlap_and_far_ones_get_a_leader() {
        // Six points where the floor gathers them, two apart in x, and one far away.
        let points = [(100, 400), (102, 400), (104, 400), (100, 400), (101, 400), (103, 400), (600, 50)];
        let sizes = [(90, 14); 7];
        let placed = place(&points, &sizes, (0..800, 0..600));
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
        let points = [(20, 30), (300, 30), (20, 300)];
        let placed = place(&points, &[(50, 12); 3], (0..800, 0..600));
        assert!(placed.iter().all(|p| p.offset == (GAP, -12 - GAP / 2) && !p.leader), "{placed:?}");
    }

    #[test]
    fn labels_stay_inside_the_plotting_area_and_off_other_points_dots() {
        // A point in the area's top-left corner: above and to the left
        // would leave the area, so its label goes below right.
        let placed = place(&[(102, 52)], &[(60, 12)], (100..700, 50..500));
        assert_eq!(placed[0].offset, (GAP, GAP / 2));
        // A label above right of the first point would cover the second's
        // dot: it goes below right instead.
        let points = [(200, 200), (230, 190)];
        let placed = place(&points, &[(60, 12); 2], (0..800, 0..600));
        let (corner, size) = corners(&points, &placed)[0];
        assert!(
            !overlaps(corner, size, (230 - DOT, 190 - DOT), (2 * DOT as u32, 2 * DOT as u32)),
            "{placed:?}"
        );
        assert_eq!(placed[0].offset, (GAP, GAP / 2));
    }

    #[test]
    fn boxes_overlap_only_when_they_share_area() {
        assert!(overlaps((0, 0), (10, 10), (5, 5), (10, 10)));
        assert!(!overlaps((0, 0), (10, 10), (10, 0), (10, 10)));
        assert!(!overlaps((0, 0), (10, 10), (0, 10), (10, 10)));
    }
}
