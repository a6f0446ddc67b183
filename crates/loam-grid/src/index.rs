//! Lexicographic numbering of boxes of integer coordinates, axis 0 fastest: the one
//! numbering of grid nodes, grid cells, mesh nodes, mesh elements and the Gauss points of
//! an element.

/// Linear index of `ijk` in a box with `dims[a]` entries along axis `a` (axis 0 fastest).
#[inline]
pub fn lexicographic_index<const D: usize>(ijk: [usize; D], dims: [usize; D]) -> usize {
    (0..D).rev().fold(0, |index, a| index * dims[a] + ijk[a])
}

/// Integer coordinates of `index` in a box with `dims[a]` entries along axis `a`: the
/// inverse of [`lexicographic_index`].
#[inline]
pub fn lexicographic_coords<const D: usize>(mut index: usize, dims: [usize; D]) -> [usize; D] {
    std::array::from_fn(|a| {
        let i = index % dims[a];
        index /= dims[a];
        i
    })
}

/// Integer coordinates of corner `k` (0..2^D) of the cell whose lowest corner is `base`:
/// bit `a` of `k` set means one step along axis `a`, so corners come in lexicographic order.
#[inline]
pub fn cell_corner<const D: usize>(base: [usize; D], k: usize) -> [usize; D] {
    std::array::from_fn(|a| base[a] + ((k >> a) & 1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn index_and_coords_are_inverse_with_axis_0_fastest() {
        let dims = [3, 4, 5];
        for index in 0..60 {
            assert_eq!(lexicographic_index(lexicographic_coords(index, dims), dims), index);
        }
        assert_eq!(lexicographic_index([1, 0, 0], dims), 1);
        assert_eq!(lexicographic_index([0, 1, 0], dims), 3);
        assert_eq!(lexicographic_index([0, 0, 1], dims), 12);
        assert_eq!(lexicographic_coords(17, dims), [2, 1, 1]);
    }
}
