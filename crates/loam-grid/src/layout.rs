//! The node layout of an analysis: which fields every active node carries and where their
//! degrees of freedom sit. A single-body mechanical analysis carries one displacement (or
//! velocity) field of D components; contact between bodies carries one such field per
//! body at every node, and coupled pore water a pressure beside them. The dofs of a node
//! are contiguous, field after field, component after component: dof = node · (dofs per
//! node) + the field's offset + the component — the numbering the block sparsity pattern
//! (`loam_solve::BlockPattern`, one block of that size per coupled node pair), the
//! constraints, the transfers and the outputs all use.

/// What a nodal field is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NodeField {
    /// The displacement (implicit) or velocity (explicit) of body `body`: D components.
    Motion { body: u32 },
    /// The pore water pressure: one component.
    PorePressure,
}

/// The fields of every active node and their dofs (module docs).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NodeLayout {
    dimension: usize,
    fields: Vec<NodeField>,
    /// Per field, the offset of its first dof within a node's; one more entry at the end
    /// (the dofs per node).
    offsets: Vec<usize>,
}

/// Why a layout cannot be made.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum LayoutError {
    #[error("a node layout needs at least one field")]
    NoField,
    #[error("a node layout is of dimension 1, 2 or 3, not {0}")]
    Dimension(usize),
    #[error("field {0:?} appears twice in a node layout")]
    Repeated(NodeField),
}

impl NodeLayout {
    /// The layout of one body's motion, D dofs a node: every analysis today.
    pub fn motion(dimension: usize) -> Self {
        Self::new(dimension, &[NodeField::Motion { body: 0 }]).expect("one motion field is a valid layout")
    }

    /// The layout of `fields` in `dimension`, in their order, each once.
    pub fn new(dimension: usize, fields: &[NodeField]) -> Result<Self, LayoutError> {
        if !(1..=3).contains(&dimension) {
            return Err(LayoutError::Dimension(dimension));
        }
        if fields.is_empty() {
            return Err(LayoutError::NoField);
        }
        if let Some((_, f)) = fields.iter().enumerate().find(|(k, f)| fields[..*k].contains(f)) {
            return Err(LayoutError::Repeated(*f));
        }
        let mut offsets = vec![0];
        for f in fields {
            let width = match f {
                NodeField::Motion { .. } => dimension,
                NodeField::PorePressure => 1,
            };
            offsets.push(offsets.last().unwrap() + width);
        }
        Ok(Self { dimension, fields: fields.to_vec(), offsets })
    }

    pub fn dimension(&self) -> usize {
        self.dimension
    }

    /// The fields, in the order of their dofs.
    pub fn fields(&self) -> &[NodeField] {
        &self.fields
    }

    /// Dofs of one node: the size of a block of the sparsity pattern.
    #[inline]
    pub fn dofs_per_node(&self) -> usize {
        *self.offsets.last().expect("a layout has a field")
    }

    /// Dofs of `nodes` nodes.
    #[inline]
    pub fn num_dofs(&self, nodes: usize) -> usize {
        nodes * self.dofs_per_node()
    }

    /// The index of `field` among the fields, if the layout has it.
    pub fn field_index(&self, field: NodeField) -> Option<usize> {
        self.fields.iter().position(|&f| f == field)
    }

    /// The dofs of field `k` within a node's, as offsets.
    #[inline]
    pub fn field_offsets(&self, k: usize) -> std::ops::Range<usize> {
        self.offsets[k]..self.offsets[k + 1]
    }

    /// Dof of component `component` of field `k` at node `node`.
    #[inline]
    pub fn dof(&self, node: usize, k: usize, component: usize) -> usize {
        debug_assert!(self.offsets[k] + component < self.offsets[k + 1], "component of the field");
        node * self.dofs_per_node() + self.offsets[k] + component
    }

    /// The node, field and component of dof `dof`.
    pub fn locate(&self, dof: usize) -> (usize, usize, usize) {
        let d = self.dofs_per_node();
        let (node, within) = (dof / d, dof % d);
        let k = self.offsets.partition_point(|&o| o <= within) - 1;
        (node, k, within - self.offsets[k])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two bodies' motion in 2D and 3D: 2 D dofs a node, body 1's after body 0's.
    #[test]
    fn two_bodies_take_two_motion_fields() {
        for d in [2, 3] {
            let layout = NodeLayout::new(d, &[NodeField::Motion { body: 0 }, NodeField::Motion { body: 1 }]).unwrap();
            assert_eq!(layout.dofs_per_node(), 2 * d);
            assert_eq!(layout.num_dofs(5), 10 * d);
            assert_eq!(layout.field_offsets(1), d..2 * d);
            assert_eq!(layout.dof(3, 1, d - 1), 3 * 2 * d + 2 * d - 1);
            assert_eq!(layout.field_index(NodeField::Motion { body: 1 }), Some(1));
            assert_eq!(layout.field_index(NodeField::PorePressure), None);
            for dof in 0..layout.num_dofs(4) {
                let (node, k, c) = layout.locate(dof);
                assert_eq!(layout.dof(node, k, c), dof);
            }
        }
    }

    /// A displacement and a pore pressure: D + 1 dofs a node, the pressure last.
    #[test]
    fn a_pressure_beside_the_displacement() {
        for d in [1, 2, 3] {
            let layout = NodeLayout::new(d, &[NodeField::Motion { body: 0 }, NodeField::PorePressure]).unwrap();
            assert_eq!(layout.dofs_per_node(), d + 1);
            assert_eq!(layout.dof(2, 1, 0), 2 * (d + 1) + d);
            assert_eq!(layout.locate(2 * (d + 1) + d), (2, 1, 0));
            assert_eq!(layout.locate(d + 1), (1, 0, 0));
        }
        assert_eq!(NodeLayout::motion(3).dofs_per_node(), 3);
    }

    #[test]
    fn invalid_layouts_are_refused() {
        assert_eq!(NodeLayout::new(2, &[]), Err(LayoutError::NoField));
        assert_eq!(NodeLayout::new(4, &[NodeField::PorePressure]), Err(LayoutError::Dimension(4)));
        let twice = [NodeField::PorePressure, NodeField::PorePressure];
        assert_eq!(NodeLayout::new(2, &twice), Err(LayoutError::Repeated(NodeField::PorePressure)));
    }
}
