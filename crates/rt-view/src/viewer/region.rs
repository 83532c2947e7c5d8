//! A rectangle of the image to render on its own (a region render): its
//! pixels get the full render's samples, bit for bit, and the rest of the
//! image stays as it was.

use std::ops::Range;

/// A non-empty rectangle of image pixels: `columns` × `rows`, half-open.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Region {
    /// The columns, left to right.
    pub columns: Range<u32>,
    /// The rows, top to bottom.
    pub rows: Range<u32>,
}

impl Region {
    /// The whole `width` × `height` image.
    pub fn whole(width: u32, height: u32) -> Self {
        Self { columns: 0..width, rows: 0..height }
    }

    /// The pixels a rectangle dragged from `a` to `b` covers, in image
    /// pixel coordinates (fractions allowed, any corner first), clipped to
    /// the `width` × `height` image: every pixel the rectangle touches.
    /// `None` if it misses the image or covers no pixel.
    pub fn spanning(a: [f32; 2], b: [f32; 2], width: u32, height: u32) -> Option<Self> {
        let span = |p: f32, q: f32, n: u32| {
            let (lo, hi) = (p.min(q).max(0.0), p.max(q).min(n as f32));
            let (first, end) = (lo.floor() as u32, (hi.ceil() as u32).min(n));
            (hi > lo && first < end).then_some(first..end)
        };
        Some(Self { columns: span(a[0], b[0], width)?, rows: span(a[1], b[1], height)? })
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.columns.len() as u32
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.rows.len() as u32
    }

    /// Whether pixel (x, y) is inside.
    pub fn contains(&self, x: u32, y: u32) -> bool {
        self.columns.contains(&x) && self.rows.contains(&y)
    }

    /// Whether the region lies inside a `width` × `height` image.
    pub fn fits(&self, width: u32, height: u32) -> bool {
        self.columns.end <= width && self.rows.end <= height && self.width() > 0 && self.height() > 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_drag_covers_every_pixel_it_touches_whichever_corner_comes_first() {
        let r = Region { columns: 2..6, rows: 1..4 };
        assert_eq!(Region::spanning([2.5, 1.2], [5.1, 3.9], 10, 8), Some(r.clone()));
        assert_eq!(Region::spanning([5.1, 3.9], [2.5, 1.2], 10, 8), Some(r.clone()));
        assert_eq!(Region::spanning([2.0, 1.0], [6.0, 4.0], 10, 8), Some(r));
        assert_eq!((Region::whole(10, 8).width(), Region::whole(10, 8).height()), (10, 8));
    }

    #[test]
    fn a_drag_is_clipped_to_the_image_and_one_that_misses_it_or_has_no_area_is_none() {
        assert_eq!(
            Region::spanning([-5.0, -5.0], [3.5, 20.0], 10, 8),
            Some(Region { columns: 0..4, rows: 0..8 })
        );
        assert_eq!(Region::spanning([11.0, 1.0], [15.0, 3.0], 10, 8), None);
        assert_eq!(Region::spanning([3.0, 1.0], [3.0, 5.0], 10, 8), None);
        assert_eq!(Region::spanning([-3.0, -3.0], [-1.0, -1.0], 10, 8), None);
    }

    #[test]
    fn containment_and_fit() {
        let r = Region { columns: 2..6, rows: 1..4 };
        assert!(r.contains(2, 1) && r.contains(5, 3) && !r.contains(6, 3) && !r.contains(2, 0));
        assert!(r.fits(6, 4) && !r.fits(5, 4) && !Region { columns: 2..2, rows: 1..4 }.fits(6, 4));
    }
}
