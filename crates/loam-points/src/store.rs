//! The store of material points, declared once: every field a point carries is a row of
//! the table at the end of this module, and from that one table follow the store itself
//! (private fields behind slices), its mutable view for the analyses ([`PointsMut`]), the
//! fields a step computes anew and exchanges at its commit ([`StateFields`]), the check of
//! lengths, the removal, reordering and appending of points, and the named columns a
//! checkpoint writes ([`PointStore::columns`]).
//!
//! The fields fall in three groups: a point's *identity*, fixed from its creation (stable
//! id, body, material, mass, initial position, volume and GIMP domain); its *state*, which
//! every step computes anew (position, velocity, F, volume, GIMP domain, stress, elastic
//! strain, and the law's history beside them); and what is *carried* from step to step by
//! the analyses that use it (the Newmark acceleration).

use crate::PointsError;
use nalgebra::{Matrix3, SVector};

/// A point's stable identity: given when the point is added, kept through removals and
/// reorderings of the others, never given again by the same store.
pub type PointId = u64;

/// A field's values as a checkpoint keeps them: floats (a vector's components or a 3 × 3
/// tensor's column by column, point after point), or integers.
#[derive(Debug, Clone, PartialEq)]
pub enum Column {
    Floats(Vec<f64>),
    Integers(Vec<u64>),
}

/// The value type of a point field, as it goes to and from a [`Column`].
trait ColumnValue: Copy {
    const WIDTH: usize;
    const INTEGER: bool;
    fn write(values: &[Self]) -> Column;
    fn read(column: &Column) -> Option<Vec<Self>>;
}

/// The floats of a [`Column`], `w` to a point, if it is one.
fn floats(column: &Column, w: usize) -> Option<&[f64]> {
    match column {
        Column::Floats(values) if values.len().is_multiple_of(w) => Some(values),
        _ => None,
    }
}

impl<const R: usize, const C: usize> ColumnValue for nalgebra::SMatrix<f64, R, C> {
    const WIDTH: usize = R * C;
    const INTEGER: bool = false;
    fn write(values: &[Self]) -> Column {
        Column::Floats(values.iter().flat_map(|m| m.iter().copied()).collect())
    }
    fn read(column: &Column) -> Option<Vec<Self>> {
        Some(floats(column, R * C)?.chunks_exact(R * C).map(Self::from_column_slice).collect())
    }
}

impl ColumnValue for f64 {
    const WIDTH: usize = 1;
    const INTEGER: bool = false;
    fn write(values: &[Self]) -> Column {
        Column::Floats(values.to_vec())
    }
    fn read(column: &Column) -> Option<Vec<Self>> {
        Some(floats(column, 1)?.to_vec())
    }
}

impl ColumnValue for u64 {
    const WIDTH: usize = 1;
    const INTEGER: bool = true;
    fn write(values: &[Self]) -> Column {
        Column::Integers(values.to_vec())
    }
    fn read(column: &Column) -> Option<Vec<Self>> {
        match column {
            Column::Integers(v) => Some(v.clone()),
            Column::Floats(_) => None,
        }
    }
}

impl ColumnValue for u32 {
    const WIDTH: usize = 1;
    const INTEGER: bool = true;
    fn write(values: &[Self]) -> Column {
        Column::Integers(values.iter().map(|&v| v as u64).collect())
    }
    fn read(column: &Column) -> Option<Vec<Self>> {
        match column {
            Column::Integers(v) => v.iter().map(|&x| u32::try_from(x).ok()).collect(),
            Column::Floats(_) => None,
        }
    }
}

/// Keep the entries of `v` whose `keep` is set, in order.
fn compact<T: Copy>(v: &mut Vec<T>, keep: &[bool]) {
    let mut w = 0;
    for r in 0..v.len() {
        if keep[r] {
            v[w] = v[r];
            w += 1;
        }
    }
    v.truncate(w);
}

/// `v` in the order `order` (entry k becomes the old entry `order[k]`), in chunks of `w`.
fn permuted<T: Copy>(v: &[T], order: &[usize], w: usize) -> Vec<T> {
    order.iter().flat_map(|&p| v[p * w..(p + 1) * w].iter().copied()).collect()
}

/// The column `name` of `columns` read as `T`, one per point of `n`, or why not.
fn read_column<T: ColumnValue>(
    columns: &dyn Fn(&str) -> Option<Column>,
    name: &'static str,
    n: Option<usize>,
) -> Result<Vec<T>, PointsError> {
    let column = columns(name).ok_or(PointsError::Column { field: name, what: "missing".into() })?;
    let kind = if T::INTEGER { "integers" } else { "floats" };
    let values = T::read(&column)
        .ok_or_else(|| PointsError::Column { field: name, what: format!("not {kind}, {} to a point", T::WIDTH) })?;
    match n {
        Some(n) if values.len() != n => Err(PointsError::FieldLength { field: name, points: n, found: values.len() }),
        _ => Ok(values),
    }
}

macro_rules! point_fields {
    (
        identity { $( $(#[$idoc:meta])* $iname:ident : $ity:ty ),* $(,)? }
        state { $( $(#[$sdoc:meta])* $sname:ident, $smut:ident : $sty:ty ),* $(,)? }
        carried { $( $(#[$cdoc:meta])* $cname:ident, $cmut:ident : $cty:ty ),* $(,)? }
    ) => {
        /// Struct-of-arrays store of material points: one entry per point in each field (the
        /// module docs). Points are added by [`PointStore::push`] and
        /// [`PointStore::fill`](crate::PointStore::fill), each with a new [`PointId`];
        /// removed by [`PointStore::retain`]; reordered by [`PointStore::reorder`].
        #[derive(Debug, Clone, Default)]
        pub struct PointStore<const D: usize> {
            $( $iname: Vec<$ity>, )*
            $( $sname: Vec<$sty>, )*
            $( $cname: Vec<$cty>, )*
            /// Per-point history variables of the material, `history_stride` per point.
            history: Vec<f64>,
            history_stride: usize,
            /// The id the next point added gets.
            next_id: PointId,
        }

        impl<const D: usize> PointStore<D> {
            $( $(#[$idoc])* #[inline] pub fn $iname(&self) -> &[$ity] { &self.$iname } )*
            $( $(#[$sdoc])* #[inline] pub fn $sname(&self) -> &[$sty] { &self.$sname } )*
            $( $(#[$sdoc])* #[inline] pub fn $smut(&mut self) -> &mut [$sty] { &mut self.$sname } )*
            $( $(#[$cdoc])* #[inline] pub fn $cname(&self) -> &[$cty] { &self.$cname } )*
            $( $(#[$cdoc])* #[inline] pub fn $cmut(&mut self) -> &mut [$cty] { &mut self.$cname } )*

            /// The length of every field but the history, by name.
            fn lengths(&self) -> Vec<(&'static str, usize)> {
                vec![
                    $( (stringify!($iname), self.$iname.len()), )*
                    $( (stringify!($sname), self.$sname.len()), )*
                    $( (stringify!($cname), self.$cname.len()), )*
                ]
            }

            /// Keep the points whose `keep` is set, in order.
            fn compact(&mut self, keep: &[bool]) {
                $( compact(&mut self.$iname, keep); )*
                $( compact(&mut self.$sname, keep); )*
                $( compact(&mut self.$cname, keep); )*
                let s = self.history_stride;
                if s > 0 {
                    let mut w = 0;
                    for (r, &k) in keep.iter().enumerate() {
                        if k {
                            self.history.copy_within(r * s..(r + 1) * s, w * s);
                            w += 1;
                        }
                    }
                    self.history.truncate(w * s);
                }
            }

            /// Put the points in the order `order`, a permutation of them.
            fn permute(&mut self, order: &[usize]) {
                $( self.$iname = permuted(&self.$iname, order, 1); )*
                $( self.$sname = permuted(&self.$sname, order, 1); )*
                $( self.$cname = permuted(&self.$cname, order, 1); )*
                self.history = permuted(&self.history, order, self.history_stride);
            }

            /// Add the points of `other` (same history stride) after these, their fields as
            /// they are.
            fn extend_fields(&mut self, other: &Self) {
                $( self.$iname.extend_from_slice(&other.$iname); )*
                $( self.$sname.extend_from_slice(&other.$sname); )*
                $( self.$cname.extend_from_slice(&other.$cname); )*
                self.history.extend_from_slice(&other.history);
            }

            /// Every field as a named column (the history `history_stride` floats to a
            /// point), and the next id as a column of one: what a checkpoint keeps of the
            /// points, bit for bit.
            pub fn columns(&self) -> Vec<(&'static str, Column)> {
                vec![
                    $( (stringify!($iname), ColumnValue::write(&self.$iname)), )*
                    $( (stringify!($sname), ColumnValue::write(&self.$sname)), )*
                    $( (stringify!($cname), ColumnValue::write(&self.$cname)), )*
                    ("history", Column::Floats(self.history.clone())),
                    ("next_id", Column::Integers(vec![self.next_id])),
                ]
            }

            /// The store [`PointStore::columns`] wrote, from the columns by name, each length
            /// checked (the point count is the ids'), and the history read as
            /// `history_stride` values a point; then [`PointStore::check`]ed.
            pub fn from_columns(
                columns: &dyn Fn(&str) -> Option<Column>,
                history_stride: usize,
            ) -> Result<Self, PointsError> {
                let id: Vec<PointId> = read_column(columns, "id", None)?;
                let n = Some(id.len());
                let mut store = Self {
                    $( $iname: read_column(columns, stringify!($iname), n)?, )*
                    $( $sname: read_column(columns, stringify!($sname), n)?, )*
                    $( $cname: read_column(columns, stringify!($cname), n)?, )*
                    history: Vec::new(),
                    history_stride,
                    next_id: 0,
                };
                let history = columns("history").ok_or(PointsError::Column { field: "history", what: "missing".into() })?;
                store.history = match floats(&history, history_stride.max(1)) {
                    Some(v) if v.len() == history_stride * id.len() => v.to_vec(),
                    _ => return Err(PointsError::Column {
                        field: "history",
                        what: format!("not {history_stride} floats to each of {} points", id.len()),
                    }),
                };
                let next: Vec<u64> = read_column(columns, "next_id", Some(1))?;
                store.next_id = next[0];
                store.check()?;
                Ok(store)
            }

            /// The mutable view of the points' identity-preserving state.
            pub fn view_mut(&mut self) -> PointsMut<'_, D> {
                PointsMut {
                    $( $iname: &self.$iname, )*
                    $( $sname: &mut self.$sname, )*
                    $( $cname: &mut self.$cname, )*
                    history: &mut self.history,
                }
            }

            /// Exchange the state fields and (where the laws keep one) the history with
            /// `fields`, each holding one value per point (the history in the laws'
            /// layout). O(1); a field of another length is a bug of the caller, and panics.
            pub fn swap_state(&mut self, fields: &mut StateFields<D>) {
                let n = self.len();
                let lengths = [$( fields.$sname.len(), )*];
                assert!(lengths.iter().all(|&l| l == n), "swap_state: fields of {lengths:?} values for {n} points");
                $( std::mem::swap(&mut self.$sname, &mut fields.$sname); )*
                if self.history_stride > 0 {
                    assert_eq!(fields.history.len(), self.history.len(), "swap_state: history of another layout");
                    std::mem::swap(&mut self.history, &mut fields.history);
                }
            }
        }

        /// Mutable view of the points' state (and of what the analyses carry), beside their
        /// identity read-only: slices, so no point can be added or removed through it and
        /// none changes its material, mass or id (the module docs).
        pub struct PointsMut<'a, const D: usize> {
            $( $(#[$idoc])* pub $iname: &'a [$ity], )*
            $( $(#[$sdoc])* pub $sname: &'a mut [$sty], )*
            $( $(#[$cdoc])* pub $cname: &'a mut [$cty], )*
            /// Every point's history, the laws' history length each.
            pub history: &'a mut [f64],
        }

        /// Whole state fields of the points, exchanged with a store's in O(1) by
        /// [`PointStore::swap_state`]: a step that computes them anew for every point
        /// commits by exchange, with no copy.
        #[derive(Debug, Default)]
        pub struct StateFields<const D: usize> {
            $( $(#[$sdoc])* pub $sname: Vec<$sty>, )*
            /// The laws' history values per point, or anything (not exchanged) where the
            /// laws keep none.
            pub history: Vec<f64>,
        }

        impl<const D: usize> StateFields<D> {
            /// One value of every field per point of `n` (the values of points beyond the
            /// old length zero), the history `max(history_stride, 1)` a point so that every
            /// point has its own chunk.
            pub fn resize(&mut self, n: usize, history_stride: usize) {
                $( self.$sname.resize(n, nalgebra::zero()); )*
                self.history.resize(n * history_stride.max(1), 0.0);
            }
        }
    };
}

point_fields! {
    identity {
        /// Stable id ([`PointId`]).
        id: PointId,
        /// The body the point belongs to.
        body: u32,
        /// Material index.
        material: u32,
        /// Mass (constant).
        mass: f64,
        /// Initial position X_p.
        position0: SVector<f64, D>,
        /// Initial volume V_p.
        volume0: f64,
        /// Initial GIMP domain half-lengths l_p0.
        half_length0: SVector<f64, D>,
    }
    state {
        /// Current position x_p.
        position, position_mut: SVector<f64, D>,
        /// Velocity v_p (dynamic analyses; zero and unused in quasi-static ones).
        velocity, velocity_mut: SVector<f64, D>,
        /// Deformation gradient F (3×3 also in plane strain, where F_zz = 1).
        deformation_gradient, deformation_gradient_mut: Matrix3<f64>,
        /// Current volume v_p.
        volume, volume_mut: f64,
        /// Current GIMP domain half-lengths l_p = l_p0 ⊙ diag(U) (iGIMP).
        half_length, half_length_mut: SVector<f64, D>,
        /// Cauchy stress σ (3×3; σ_zz of plane strain included). Tension positive.
        stress, stress_mut: Matrix3<f64>,
        /// Elastic strain state: b^e (finite strain, identity when unstrained) or ε^e
        /// (small strain, zero when unstrained). The model sets which when it is built.
        elastic_strain, elastic_strain_mut: Matrix3<f64>,
    }
    carried {
        /// Acceleration a_p (implicit Newmark dynamics).
        acceleration, acceleration_mut: SVector<f64, D>,
    }
}

/// What [`PointStore::retain`] did: for every point before, its index after (`None` for a
/// removed one).
#[derive(Debug, Clone, PartialEq)]
pub struct Renumbering {
    new_index: Vec<Option<u32>>,
}

impl Renumbering {
    /// The index after of the point at `old` before, if it was kept.
    pub fn new_index(&self, old: usize) -> Option<usize> {
        self.new_index[old].map(|i| i as usize)
    }

    /// How many points were removed.
    pub fn removed(&self) -> usize {
        self.new_index.iter().filter(|i| i.is_none()).count()
    }
}

impl<const D: usize> PointStore<D> {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn len(&self) -> usize {
        self.position.len()
    }

    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    pub fn history_stride(&self) -> usize {
        self.history_stride
    }

    /// History slice of point `p`.
    #[inline]
    pub fn history(&self, p: usize) -> &[f64] {
        &self.history[p * self.history_stride..(p + 1) * self.history_stride]
    }

    /// Every point's history, `history_stride` values each.
    pub fn history_values(&self) -> &[f64] {
        &self.history
    }

    /// The id the next point added will get.
    pub fn next_id(&self) -> PointId {
        self.next_id
    }

    /// Size the history buffer to `stride` values per point and let `init` set each
    /// point's initial history.
    pub fn init_history(&mut self, stride: usize, mut init: impl FnMut(usize, &mut [f64])) {
        self.history_stride = stride;
        self.history.clear();
        self.history.resize(stride * self.len(), 0.0);
        if stride > 0 {
            for (p, h) in self.history.chunks_mut(stride).enumerate() {
                init(p, h);
            }
        }
    }

    /// Set every point's elastic strain state (identity for b^e, zero for ε^e).
    pub fn reset_elastic_strain(&mut self, value: Matrix3<f64>) {
        self.elastic_strain.iter_mut().for_each(|e| *e = value);
    }

    /// Put points `range` in body `body` (while the store is being built).
    pub fn assign_body(&mut self, range: std::ops::Range<usize>, body: u32) {
        self.body[range].iter_mut().for_each(|b| *b = body);
    }

    /// Total mass.
    pub fn total_mass(&self) -> f64 {
        self.mass.iter().sum()
    }

    /// Linear momentum Σ m_p v_p.
    pub fn momentum(&self) -> SVector<f64, D> {
        self.mass.iter().zip(&self.velocity).map(|(m, v)| v * *m).sum()
    }

    /// Kinetic energy ½ Σ m_p |v_p|².
    pub fn kinetic_energy(&self) -> f64 {
        0.5 * self.mass.iter().zip(&self.velocity).map(|(m, v)| m * v.norm_squared()).sum::<f64>()
    }

    /// The point whose initial position is nearest `x`; of equally near points the one of
    /// least id, so that the points' order does not matter. `None` without points.
    pub fn nearest_at_start(&self, x: &SVector<f64, D>) -> Option<usize> {
        (0..self.len())
            .map(|p| ((self.position0[p] - x).norm_squared(), self.id[p], p))
            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
            .map(|(_, _, p)| p)
    }

    /// The largest distance a point has moved from its initial position.
    pub fn max_displacement(&self) -> f64 {
        self.position.iter().zip(&self.position0).map(|(x, x0)| (x - x0).norm()).fold(0.0, f64::max)
    }

    /// Check what every user of the store indexes: one value of every field per point, the
    /// history `history_stride` a point, distinct ids below the next id, and each point's
    /// position, volume and mass finite, volume and mass positive, velocity finite.
    pub fn check(&self) -> Result<(), PointsError> {
        let n = self.len();
        if let Some((field, found)) = self.lengths().into_iter().find(|&(_, len)| len != n) {
            return Err(PointsError::FieldLength { field, points: n, found });
        }
        if self.history.len() != n * self.history_stride {
            let found = self.history.len();
            return Err(PointsError::FieldLength { field: "history", points: n * self.history_stride, found });
        }
        let bad = |point: usize, what: String| Err(PointsError::Point { point, what });
        let mut ids = self.id.clone();
        ids.sort_unstable();
        if let Some(w) = ids.windows(2).find(|w| w[0] == w[1]) {
            let point = self.id.iter().position(|&i| i == w[0]).unwrap_or(0);
            return bad(point, format!("its id {} is another point's too", w[0]));
        }
        if let Some(&last) = ids.last().filter(|&&last| last >= self.next_id) {
            let point = self.id.iter().position(|&i| i == last).unwrap_or(0);
            return bad(point, format!("its id {last} is not below the next id {}", self.next_id));
        }
        for p in 0..n {
            if !(self.position[p].iter().chain(self.velocity[p].iter()).all(|c| c.is_finite())) {
                return bad(p, "its position and velocity must be finite".into());
            }
            let (v, m) = (self.volume[p], self.mass[p]);
            if !(v.is_finite() && v > 0.0 && m.is_finite() && m > 0.0) {
                return bad(p, format!("volume {v} and mass {m}; both must be positive and finite"));
            }
        }
        Ok(())
    }

    /// Add one point, unstrained and at rest, in body 0, with the next id.
    pub fn push(&mut self, x: SVector<f64, D>, volume: f64, density: f64, half_length: SVector<f64, D>, material: u32) {
        self.id.push(self.next_id);
        self.next_id += 1;
        self.body.push(0);
        self.material.push(material);
        self.mass.push(density * volume);
        self.position0.push(x);
        self.volume0.push(volume);
        self.half_length0.push(half_length);
        self.position.push(x);
        self.velocity.push(SVector::zeros());
        self.deformation_gradient.push(Matrix3::identity());
        self.volume.push(volume);
        self.half_length.push(half_length);
        self.stress.push(Matrix3::zeros());
        self.elastic_strain.push(Matrix3::identity());
        self.acceleration.push(SVector::zeros());
        self.history.extend(std::iter::repeat_n(0.0, self.history_stride));
    }

    /// Remove the points for which `keep(p)` is false, the others keeping their order and
    /// ids; returns where each point went.
    pub fn retain(&mut self, keep: impl Fn(usize) -> bool) -> Renumbering {
        let mask: Vec<bool> = (0..self.len()).map(keep).collect();
        let mut next = 0u32;
        let new_index = mask
            .iter()
            .map(|&k| {
                k.then(|| {
                    next += 1;
                    next - 1
                })
            })
            .collect();
        self.compact(&mask);
        Renumbering { new_index }
    }

    /// Put the points in the order `order` (point k becomes the point at `order[k]`);
    /// refused unless `order` is a permutation of the points.
    pub fn reorder(&mut self, order: &[usize]) -> Result<(), PointsError> {
        let mut seen = vec![false; self.len()];
        let valid = order.len() == self.len()
            && order.iter().all(|&p| p < seen.len() && !std::mem::replace(&mut seen[p], true));
        if !valid {
            return Err(PointsError::Reorder(self.len()));
        }
        self.permute(order);
        Ok(())
    }

    /// Add the points of `other` after these, each with a new id (its own are dropped), in
    /// its bodies, states and history (which must have this store's stride, or be empty
    /// with a stride of 0 where this one keeps none); returns the index of the first.
    pub fn append(&mut self, other: &PointStore<D>) -> Result<usize, PointsError> {
        if other.history_stride != self.history_stride {
            return Err(PointsError::HistoryStride { found: other.history_stride, expected: self.history_stride });
        }
        let first = self.len();
        let ids = self.next_id..self.next_id + other.len() as u64;
        self.extend_fields(other);
        self.id[first..].iter_mut().zip(ids).for_each(|(id, new)| *id = new);
        self.next_id += other.len() as u64;
        Ok(first)
    }

    /// Make every point the ring it sweeps about the y axis, x its radius: its mass and
    /// volumes times 2π x at its place (an axisymmetric model's points, whose volumes were
    /// areas of the meridian plane).
    pub fn revolve(&mut self) {
        for p in 0..self.len() {
            let ring = std::f64::consts::TAU * self.position[p][0];
            self.mass[p] *= ring;
            self.volume0[p] *= ring;
            self.volume[p] *= ring;
        }
    }

    /// The order of the points by ascending id (what outputs are written in), or `None`
    /// where they are in it already.
    pub fn id_order(&self) -> Option<Vec<usize>> {
        if self.id.windows(2).all(|w| w[0] < w[1]) {
            return None;
        }
        let mut order: Vec<usize> = (0..self.len()).collect();
        order.sort_unstable_by_key(|&p| self.id[p]);
        Some(order)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector2;

    /// Four points with distinct states and a history of 2 each.
    fn four() -> PointStore<2> {
        let mut s = PointStore::<2>::new();
        for k in 0..4 {
            s.push(Vector2::new(k as f64, 0.5), 0.25, 2.0, Vector2::repeat(0.25), k as u32 % 2);
        }
        s.init_history(2, |p, h| h.iter_mut().enumerate().for_each(|(i, v)| *v = (10 * p + i) as f64));
        for p in 0..4 {
            s.velocity_mut()[p] = Vector2::new(0.0, p as f64);
            s.stress_mut()[p] = Matrix3::identity() * -(p as f64);
        }
        s
    }

    /// Removing points keeps the others' order, ids, state and history, and says where
    /// each point went; the removed ids are not given again.
    #[test]
    fn retain_keeps_the_rest_in_order_with_their_ids() {
        let mut s = four();
        let renumbering = s.retain(|p| p != 1);
        assert_eq!(s.len(), 3);
        assert_eq!(s.id(), &[0, 2, 3]);
        assert_eq!(
            (renumbering.new_index(0), renumbering.new_index(1), renumbering.new_index(3)),
            (Some(0), None, Some(2))
        );
        assert_eq!(renumbering.removed(), 1);
        assert_eq!(s.position()[1], Vector2::new(2.0, 0.5));
        assert_eq!(s.velocity()[2], Vector2::new(0.0, 3.0));
        assert_eq!(s.history(1), &[20.0, 21.0]);
        assert_eq!(s.material(), &[0, 0, 1]);
        s.check().unwrap();
        s.push(Vector2::new(9.0, 0.5), 0.25, 2.0, Vector2::repeat(0.25), 0);
        assert_eq!(s.id()[3], 4, "the next id, not a removed one");
    }

    /// A reordering moves every field of a point together; outputs find the id order again;
    /// an order that is not a permutation is refused and changes nothing.
    #[test]
    fn reorder_moves_whole_points_and_id_order_undoes_it() {
        let mut s = four();
        let before = s.clone();
        s.reorder(&[2, 0, 3, 1]).unwrap();
        assert_eq!(s.id(), &[2, 0, 3, 1]);
        assert_eq!(s.history(0), &[20.0, 21.0]);
        assert_eq!(s.stress()[3], Matrix3::identity() * -1.0);
        let order = s.id_order().unwrap();
        assert_eq!(order, vec![1, 3, 0, 2]);
        s.reorder(&order).unwrap();
        assert_eq!(s.columns(), before.columns());
        assert_eq!(s.id_order(), None);
        for bad in [vec![0, 1, 2], vec![0, 1, 1, 2], vec![0, 1, 2, 4]] {
            assert!(matches!(s.reorder(&bad), Err(PointsError::Reorder(4))));
        }
        assert_eq!(s.columns(), before.columns());
    }

    /// Appended points get new ids after every id given, and keep their fields.
    #[test]
    fn append_gives_new_ids() {
        let mut s = four();
        s.retain(|p| p != 3);
        let other = four();
        assert_eq!(s.append(&other).unwrap(), 3);
        assert_eq!(s.id(), &[0, 1, 2, 4, 5, 6, 7]);
        assert_eq!(s.history(6), &[30.0, 31.0]);
        s.check().unwrap();
        let mut bare = PointStore::<2>::new();
        bare.push(Vector2::zeros(), 1.0, 1.0, Vector2::repeat(0.5), 0);
        assert!(matches!(s.append(&bare), Err(PointsError::HistoryStride { found: 0, expected: 2 })));
    }

    /// The columns give the same store back, bit for bit, after a removal too; a column of
    /// the wrong length or kind is refused by name.
    #[test]
    fn columns_round_trip() {
        let mut s = four();
        s.retain(|p| p != 0);
        let columns = s.columns();
        let get = |name: &str| columns.iter().find(|(n, _)| *n == name).map(|(_, c)| c.clone());
        let back = PointStore::<2>::from_columns(&get, 2).unwrap();
        assert_eq!(back.columns(), columns);
        assert_eq!(back.next_id(), 4);
        let short = |name: &str| match name {
            "mass" => Some(Column::Floats(vec![1.0])),
            _ => get(name),
        };
        assert!(matches!(
            PointStore::<2>::from_columns(&short, 2),
            Err(PointsError::FieldLength { field: "mass", points: 3, found: 1 })
        ));
        let floats_for_ids = |name: &str| match name {
            "material" => Some(Column::Floats(vec![0.0; 3])),
            _ => get(name),
        };
        assert!(matches!(
            PointStore::<2>::from_columns(&floats_for_ids, 2),
            Err(PointsError::Column { field: "material", .. })
        ));
        assert!(matches!(PointStore::<2>::from_columns(&get, 3), Err(PointsError::Column { field: "history", .. })));
    }

    /// The state fields exchange whole with a store's, history included.
    #[test]
    fn swap_state_exchanges_the_state() {
        let mut s = four();
        let mut fields = StateFields::<2>::default();
        fields.resize(4, 2);
        fields.position[2] = Vector2::new(7.0, 7.0);
        fields.history[5] = 99.0;
        s.swap_state(&mut fields);
        assert_eq!(s.position()[2], Vector2::new(7.0, 7.0));
        assert_eq!(s.history(2), &[0.0, 99.0]);
        assert_eq!(fields.position[2], Vector2::new(2.0, 0.5));
    }
}
