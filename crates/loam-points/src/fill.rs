//! The generation of points from shapes: the centres of an n^D subdivision of every grid
//! cell that the shape covers, each with the volume of its sub-cell.

use crate::{PointStore, PointsError, Shape};
use loam_grid::{lexicographic_coords, Grid};
use nalgebra::SVector;

impl<const D: usize> PointStore<D> {
    /// Fill `shape` with `points_per_cell`^D points per grid cell, at the centres of the
    /// sub-cells whose centre lies inside the shape. Returns the number of points added; a
    /// failing fill leaves the store unchanged.
    pub fn fill(
        &mut self,
        grid: &Grid<D>,
        shape: &Shape<D>,
        points_per_cell: usize,
        density: f64,
        material: u32,
    ) -> Result<usize, PointsError> {
        check_points_per_cell(points_per_cell)?;
        if !(density.is_finite() && density > 0.0) {
            return Err(PointsError::Density(density));
        }
        let n = points_per_cell;
        let sub = grid.cell_size() / n as f64;
        let volume = grid.cell_volume() / (n.pow(D as u32)) as f64;
        let new_points = sub_cell_centres(grid, shape, &sub)?;
        for &x in &new_points {
            self.push(x, volume, density, sub / 2.0, material);
        }
        Ok(new_points.len())
    }
}

/// The sub-cells of size `sub` (aligned with the grid) that cover `shape`'s bounding box:
/// the index of the first along each axis and their count along each axis; an error when
/// there is none.
fn sub_cell_range<const D: usize>(
    grid: &Grid<D>,
    shape: &Shape<D>,
    sub: &SVector<f64, D>,
) -> Result<([i64; D], [usize; D]), PointsError> {
    let (lo, hi) = shape.bounds()?;
    let origin = grid.origin();
    // Sub-cell index ranges covering the shape's bounding box. A box that reaches more than
    // one sub-cell beyond the grid is refused at once (the fill refuses any centre in the
    // layer just outside): a bounding box of 1e300 cells is never walked (it used to be, by
    // `loam check` on a mistyped cell size), and a shape that reaches out between centres
    // is not cut to the grid silently.
    let sub_cells = |a: usize| ((grid.extent_max()[a] - origin[a]) / sub[a]).round() as i64;
    let first: [i64; D] = std::array::from_fn(|a| ((lo[a] - origin[a]) / sub[a] - 0.5).ceil() as i64);
    let last: [i64; D] = std::array::from_fn(|a| ((hi[a] - origin[a]) / sub[a] - 0.5).floor() as i64);
    if (0..D).any(|a| first[a] < -1 || last[a] > sub_cells(a)) {
        return Err(PointsError::BeyondGrid {
            lo: lo.iter().copied().collect(),
            hi: hi.iter().copied().collect(),
            min: origin.iter().copied().collect(),
            max: grid.extent_max().iter().copied().collect(),
        });
    }
    if (0..D).any(|a| first[a] > last[a]) {
        return Err(PointsError::EmptyRegion(format!("bounds {:?} to {:?}", lo.as_slice(), hi.as_slice())));
    }
    Ok((first, std::array::from_fn(|a| (last[a] - first[a] + 1) as usize)))
}

/// How many points [`PointStore::fill`] would add, without allocating them: at most the
/// sub-cells of the shape's bounding box (`exact_up_to` `None`, no shape test), or exactly,
/// every centre tested but the count stopped at `exact_up_to` (a memory estimate only needs
/// to know that a limit is passed). Refuses what the fill refuses about `points_per_cell`.
pub fn fill_count<const D: usize>(
    grid: &Grid<D>,
    shape: &Shape<D>,
    points_per_cell: usize,
    exact_up_to: Option<u64>,
) -> Result<u64, PointsError> {
    check_points_per_cell(points_per_cell)?;
    let sub = grid.cell_size() / points_per_cell as f64;
    let (first, dims) = sub_cell_range(grid, shape, &sub)?;
    let Some(cap) = exact_up_to else { return Ok(dims.iter().fold(1u64, |n, &d| n.saturating_mul(d as u64))) };
    Ok(centres_in(grid, shape, first, dims, sub).take(cap.min(usize::MAX as u64) as usize).count() as u64)
}

/// Points per cell and axis, 1 to 8.
fn check_points_per_cell(points_per_cell: usize) -> Result<(), PointsError> {
    if points_per_cell == 0 || points_per_cell > 8 {
        return Err(PointsError::PointsPerCell(points_per_cell));
    }
    Ok(())
}

/// The centres of the sub-cells of the range `first`, `dims` (size `sub`, axis 0 fastest)
/// that lie inside `shape`.
fn centres_in<'a, const D: usize>(
    grid: &'a Grid<D>,
    shape: &'a Shape<D>,
    first: [i64; D],
    dims: [usize; D],
    sub: SVector<f64, D>,
) -> impl Iterator<Item = SVector<f64, D>> + 'a {
    let origin = grid.origin();
    (0..dims.iter().product())
        .map(move |k| {
            let ijk = lexicographic_coords(k, dims);
            SVector::from_fn(|a, _| origin[a] + ((first[a] + ijk[a] as i64) as f64 + 0.5) * sub[a])
        })
        .filter(|x| shape.contains(x))
}

/// The centres of the sub-cells of size `sub` (aligned with the grid) that lie inside
/// `shape`, axis 0 fastest; an error when there is none or one lies outside the grid.
fn sub_cell_centres<const D: usize>(
    grid: &Grid<D>,
    shape: &Shape<D>,
    sub: &SVector<f64, D>,
) -> Result<Vec<SVector<f64, D>>, PointsError> {
    let (lo, hi) = shape.bounds()?;
    let empty = || PointsError::EmptyRegion(format!("bounds {:?} to {:?}", lo.as_slice(), hi.as_slice()));
    let origin = grid.origin();
    let (first, dims) = sub_cell_range(grid, shape, sub)?;
    let mut centres = Vec::new();
    for x in centres_in(grid, shape, first, dims, *sub) {
        if !grid.contains(&x) {
            return Err(PointsError::OutsideGrid {
                position: x.iter().copied().collect(),
                min: origin.iter().copied().collect(),
                max: grid.extent_max().iter().copied().collect(),
            });
        }
        centres.push(x);
    }
    if centres.is_empty() {
        return Err(empty());
    }
    Ok(centres)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use nalgebra::{Vector2, Vector3};

    #[test]
    fn box_fill_conserves_volume_and_mass() {
        let g = Grid::<2>::new(Vector2::zeros(), Vector2::new(0.5, 0.25), [4, 8]).unwrap();
        let mut s = PointStore::<2>::new();
        let n =
            s.fill(&g, &Shape::Box { min: Vector2::new(0.0, 0.0), max: Vector2::new(1.0, 1.5) }, 2, 2000.0, 0).unwrap();
        // 2 x 6 cells, 4 points each.
        assert_eq!(n, 48);
        assert_relative_eq!(s.volume().iter().sum::<f64>(), 1.5, epsilon = 1e-12);
        assert_relative_eq!(s.total_mass(), 3000.0, epsilon = 1e-9);
        assert_eq!(s.half_length()[0], Vector2::new(0.125, 0.0625));
        assert_eq!(s.position()[0], Vector2::new(0.125, 0.0625));
    }

    /// The count without filling: exact equals the fill's; the bound is the bounding box's
    /// sub-cells (a disc of radius 1 at 4 points per unit cell: 64 in the box, 52 inside).
    #[test]
    fn fill_count_bounds_and_counts_the_fill() {
        let g = Grid::<2>::new(Vector2::zeros(), Vector2::new(0.5, 0.5), [8, 8]).unwrap();
        let disc = Shape::Ball { centre: Vector2::new(2.0, 2.0), radius: 1.0 };
        let n = PointStore::<2>::new().fill(&g, &disc, 2, 1.0, 0).unwrap() as u64;
        assert_eq!(fill_count(&g, &disc, 2, Some(u64::MAX)).unwrap(), n);
        assert_eq!(fill_count(&g, &disc, 2, Some(10)).unwrap(), 10);
        assert_eq!(fill_count(&g, &disc, 2, None).unwrap(), 64);
        assert!(matches!(fill_count(&g, &disc, 9, None), Err(PointsError::PointsPerCell(9))));
        // Centres (i + ½)/4 from 1 within the unit circle about (2, 2): 52, counted by hand.
        assert_eq!(n, 52);
    }

    /// A prism of a right triangle (legs 8 and 4 in x and z) across y from 1 to 4: its
    /// points are those of the triangle's fill repeated along y, volume 16 × 3 = 48 to the
    /// staircase of the diagonal; and the same volume as a box cut by the hypotenuse's plane.
    #[test]
    fn a_prism_and_a_cut_box_fill_the_extruded_triangle() {
        let g = Grid::<3>::new(Vector3::zeros(), Vector3::new(1.0, 1.0, 1.0), [10, 6, 6]).unwrap();
        let tri = vec![Vector2::new(0.0, 0.0), Vector2::new(8.0, 0.0), Vector2::new(0.0, 4.0)];
        let mut prism = PointStore::<3>::new();
        prism.fill(&g, &Shape::Prism { section: tri.clone(), axis: 1, from: 1.0, to: 4.0 }, 2, 1.0, 0).unwrap();
        let g2 = Grid::<2>::new(Vector2::zeros(), Vector2::new(1.0, 1.0), [10, 6]).unwrap();
        let mut flat = PointStore::<2>::new();
        flat.fill(&g2, &Shape::Polygon(tri), 2, 1.0, 0).unwrap();
        assert_eq!(prism.len(), flat.len() * 6, "two points per cell over three cells in y");
        let volume: f64 = prism.volume().iter().sum();
        assert_relative_eq!(volume, flat.volume().iter().sum::<f64>() * 3.0, epsilon = 1e-9);
        assert!(prism.position().iter().all(|x| x[1] > 1.0 && x[1] < 4.0 && x[0] / 8.0 + x[2] / 4.0 <= 1.0));
        // The same solid: the box [0, 8] × [1, 4] × [0, 4] less the side of x/8 + z/4 > 1.
        let cut = Shape::CutBox {
            min: Vector3::new(0.0, 1.0, 0.0),
            max: Vector3::new(8.0, 4.0, 4.0),
            point: Vector3::new(8.0, 0.0, 0.0),
            normal: Vector3::new(0.5, 0.0, 1.0),
        };
        let mut boxed = PointStore::<3>::new();
        boxed.fill(&g, &cut, 2, 1.0, 0).unwrap();
        assert_eq!(boxed.position(), prism.position());
        assert!(matches!(cut.boundary(0.5), Err(PointsError::NoSurface("CutBox"))));
        let flat_prism = Shape::<2>::Prism { section: vec![], axis: 1, from: 0.0, to: 1.0 };
        assert!(matches!(PointStore::<2>::new().fill(&g2, &flat_prism, 2, 1.0, 0), Err(PointsError::Prism { .. })));
    }

    #[test]
    fn polygon_fill_of_a_triangle() {
        let g = Grid::<2>::new(Vector2::zeros(), Vector2::new(1.0, 1.0), [10, 10]).unwrap();
        let mut s = PointStore::<2>::new();
        let tri = vec![Vector2::new(0.0, 0.0), Vector2::new(8.0, 0.0), Vector2::new(0.0, 8.0)];
        s.fill(&g, &Shape::Polygon(tri), 4, 1.0, 0).unwrap();
        // Area 32; sub-cell sampling converges to it, off by the diagonal's half sub-cells.
        let area: f64 = s.volume().iter().sum();
        assert!((area - 32.0).abs() < 8.0 * 0.25, "area {area}");
    }

    #[test]
    fn three_dimensional_box() {
        let g = Grid::<3>::new(Vector3::zeros(), Vector3::new(0.4, 0.1, 0.4), [1, 8, 1]).unwrap();
        let mut s = PointStore::<3>::new();
        let n =
            s.fill(&g, &Shape::Box { min: Vector3::zeros(), max: Vector3::new(0.4, 0.8, 0.4) }, 2, 50.0, 0).unwrap();
        assert_eq!(n, 64);
        assert_relative_eq!(s.volume().iter().sum::<f64>(), 0.128, epsilon = 1e-12);
    }

    #[test]
    fn bad_fills_are_refused() {
        let g = Grid::<2>::new(Vector2::zeros(), Vector2::new(1.0, 1.0), [2, 2]).unwrap();
        let mut s = PointStore::<2>::new();
        // Half a sub-cell out: the centre at x = 2.25 is in the shape and outside the grid.
        let b = Shape::Box { min: Vector2::new(0.0, 0.0), max: Vector2::new(2.3, 1.0) };
        assert!(matches!(s.fill(&g, &b, 2, 1.0, 0), Err(PointsError::OutsideGrid { .. })));
        // A cell out: refused by its bounds, before any centre is walked.
        let b = Shape::Box { min: Vector2::new(0.0, 0.0), max: Vector2::new(3.0, 1.0) };
        assert!(matches!(s.fill(&g, &b, 2, 1.0, 0), Err(PointsError::BeyondGrid { .. })));
        let thin = Shape::Box { min: Vector2::new(0.1, 0.1), max: Vector2::new(0.2, 0.2) };
        assert!(matches!(s.fill(&g, &thin, 2, 1.0, 0), Err(PointsError::EmptyRegion(_))));
        let ok = Shape::Box { min: Vector2::new(0.0, 0.0), max: Vector2::new(1.0, 1.0) };
        assert!(matches!(s.fill(&g, &ok, 0, 1.0, 0), Err(PointsError::PointsPerCell(0))));
        assert!(matches!(s.fill(&g, &ok, 2, -1.0, 0), Err(PointsError::Density(_))));
        assert!(s.is_empty());
    }

    /// The disk of V5 (radius 0.2 on a 20×20 unit grid, 2×2 points per cell): sub-cell
    /// sampling gives an area within one ring of sub-cells of πr² (perimeter 2πr × sub-cell
    /// width 0.025 ≈ 0.031 is a loose bound; the sampling error is far smaller on average).
    #[test]
    fn ball_fill_of_a_disk() {
        let g = Grid::<2>::new(Vector2::zeros(), Vector2::new(0.05, 0.05), [20, 20]).unwrap();
        let mut s = PointStore::<2>::new();
        s.fill(&g, &Shape::Ball { centre: Vector2::new(0.2, 0.2), radius: 0.2 }, 2, 1000.0, 0).unwrap();
        let area: f64 = s.volume().iter().sum();
        let exact = std::f64::consts::PI * 0.04;
        assert!((area - exact).abs() < 2.0 * std::f64::consts::PI * 0.2 * 0.025, "area {area} vs {exact}");
        assert!(s.position().iter().all(|x| (x - Vector2::new(0.2, 0.2)).norm() <= 0.2));
        let bad = Shape::Ball { centre: Vector2::new(0.5, 0.5), radius: -1.0 };
        assert!(matches!(s.fill(&g, &bad, 2, 1.0, 0), Err(PointsError::Radius(_))));
    }
}
