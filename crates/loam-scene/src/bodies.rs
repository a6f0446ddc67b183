//! The bodies part of a scene: each body's material and shape, filled with material
//! points on the grid or, with the updated Lagrangian FEM reference, meshed as a block;
//! and the bodies' initial velocities.

use super::locate::Seg;
use super::{BodySpec, LoadedScene, MethodSpec, SceneError, ShapeSpec, VelocitySpec};
use loam_grid::{FeMesh, Grid, MeshError};
use loam_model::Model;
use loam_points::{PointStore, Shape};
use nalgebra::{SVector, Vector2};

/// What the bodies become: material points, or one mesh of blocks (one block per body,
/// each with its density and material index).
pub(super) enum Bodies<const D: usize> {
    Points(Box<PointStore<D>>),
    Mesh { mesh: FeMesh<D>, density: Vec<f64>, material: Vec<u32> },
}

impl LoadedScene {
    /// The bodies, at least one, discretised by the scene's method.
    pub(super) fn bodies<const D: usize>(&self, grid: &Grid<D>) -> Result<Bodies<D>, SceneError> {
        if self.scene.bodies.is_empty() {
            return Err(self.error(
                &[Seg::Key("bodies")],
                "no bodies: add at least one Body(material: ..., shape: Box(min: [...], max: [...]))",
            ));
        }
        let bodies = &self.scene.bodies;
        for (i, b) in bodies.iter().enumerate() {
            let named = |e: &BodySpec| !b.name.is_empty() && e.name == b.name;
            if let Some(j) = bodies[..i].iter().position(named) {
                return Err(self.error(
                    &body_key(i, "name"),
                    format!("body {i} is called {:?}, as body {j} is; body names must differ", b.name),
                ));
            }
        }
        match self.scene.method {
            MethodSpec::Mpm => self.material_points(grid),
            MethodSpec::UpdatedLagrangianFem => self.fem_blocks(grid),
        }
    }

    /// Material points filling each body, with the body's initial velocity.
    fn material_points<const D: usize>(&self, grid: &Grid<D>) -> Result<Bodies<D>, SceneError> {
        let mut points = PointStore::<D>::new();
        let mut shapes = Vec::new();
        for (i, b) in self.scene.bodies.iter().enumerate() {
            let material = self.body_material(i, b)?;
            let shape = self.shape::<D>(i, b)?;
            let density = self.scene.materials[material].density;
            let added = points
                .fill(grid, &shape, b.points_per_cell, density, material as u32)
                .map_err(|e| self.error(&body_key(i, "shape"), format!("body {i}: {e}")))?;
            let first = points.len() - added;
            points.assign_body(first..points.len(), i as u32);
            if !b.may_overlap {
                self.check_overlap(i, &points.position()[first..], &shapes)?;
            }
            if let Some(v) = &b.velocity {
                let field = self.velocity_field::<D>(v, i)?;
                for p in first..points.len() {
                    points.velocity_mut()[p] = field(&points.position_mut()[p]);
                    if !(points.mass()[p] * points.velocity()[p].norm_squared()).is_finite() {
                        return Err(self.error(
                            &body_key(i, "velocity"),
                            format!(
                                "body {i}: the velocity {:?} at {:?} makes the kinetic energy overflow; is a component mistyped?",
                                points.velocity()[p].as_slice(),
                                points.position()[p].as_slice()
                            ),
                        ));
                    }
                }
            }
            shapes.push(shape);
        }
        Ok(Bodies::Points(Box::new(points)))
    }

    /// Refuse body `i` if one of its points lies inside an earlier body's shape: the points
    /// of both would fill the overlap (two identical bodies double the mass without a word).
    fn check_overlap<const D: usize>(
        &self,
        i: usize,
        positions: &[SVector<f64, D>],
        earlier: &[Shape<D>],
    ) -> Result<(), SceneError> {
        for x in positions {
            if let Some(j) = earlier.iter().position(|s| s.contains(x)) {
                return Err(self.error(
                    &body_key(i, "shape"),
                    format!(
                        "body {i} overlaps body {j} (at {:?}): the points of both would fill the overlap and \
                         its mass would count twice; move one, or set may_overlap: true on body {i} if that is meant",
                        x.as_slice()
                    ),
                ));
            }
        }
        Ok(())
    }

    /// One mesh block per body, of elements about one grid cell in size. The initial
    /// velocities are set on the model's Gauss points (`fem_velocities`).
    fn fem_blocks<const D: usize>(&self, grid: &Grid<D>) -> Result<Bodies<D>, SceneError> {
        let mut mesh: Option<FeMesh<D>> = None;
        let (mut density, mut material) = (Vec::new(), Vec::new());
        for (i, b) in self.scene.bodies.iter().enumerate() {
            let mi = self.body_material(i, b)?;
            let shape = self.shape::<D>(i, b)?;
            let block = self.fem_block(i, b, shape, grid)?;
            match &mut mesh {
                None => mesh = Some(block),
                Some(m) => m
                    .append(block)
                    .map_err(|e| self.error(&body_key(i, "points_per_cell"), format!("body {i}: {e}")))?,
            }
            density.push(self.scene.materials[mi].density);
            material.push(mi as u32);
        }
        let mesh = mesh.expect("bodies() refuses a scene without bodies");
        Ok(Bodies::Mesh { mesh, density, material })
    }

    /// The block meshing body `i`, a Box; `points_per_cell` is the Gauss order.
    fn fem_block<const D: usize>(
        &self,
        i: usize,
        b: &BodySpec,
        shape: Shape<D>,
        grid: &Grid<D>,
    ) -> Result<FeMesh<D>, SceneError> {
        let Shape::Box { min, max } = shape else {
            return Err(self.error(
                &body_key(i, "shape"),
                format!("body {i}: the updated Lagrangian FEM meshes Box bodies only; use a Box or method: Mpm"),
            ));
        };
        let elements = fem_elements(&min, &max, grid).map(|n| n as usize);
        FeMesh::block(min, max, elements, b.points_per_cell).map_err(|e| {
            let key = if matches!(e, MeshError::GaussOrder(_)) { "points_per_cell" } else { "shape" };
            self.error(
                &body_key(i, key),
                format!("body {i}: {e} (with method UpdatedLagrangianFem, points_per_cell is the Gauss order)"),
            )
        })
    }

    /// The index of body `i`'s material, which must be defined.
    fn body_material(&self, i: usize, b: &BodySpec) -> Result<usize, SceneError> {
        let materials = &self.scene.materials;
        materials.iter().position(|m| m.name == b.material).ok_or_else(|| {
            let names: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
            self.error(
                &body_key(i, "material"),
                format!("body {i} uses material \"{}\", which is not defined; defined: {names:?}", b.material),
            )
        })
    }

    /// Body `i`'s shape, its points with `D` finite components.
    pub(super) fn shape<const D: usize>(&self, i: usize, b: &BodySpec) -> Result<Shape<D>, SceneError> {
        self.shape_at(&b.shape, &body_key(i, "shape"))
    }

    /// The shape `spec` at `path` in the file, its points with `D` finite components.
    pub(super) fn shape_at<const D: usize>(&self, spec: &ShapeSpec, path: &[Seg]) -> Result<Shape<D>, SceneError> {
        let at = |key| [path, &[Seg::Key(key)]].concat();
        Ok(match spec {
            ShapeSpec::Box { min, max } => Shape::Box {
                min: self.vector(min, &at("min"), "Box min")?,
                max: self.vector(max, &at("max"), "Box max")?,
            },
            ShapeSpec::Ball { centre, radius } => {
                Shape::Ball { centre: self.vector(centre, &at("centre"), "Ball centre")?, radius: *radius }
            }
            ShapeSpec::Polygon { vertices } => {
                if D != 2 {
                    return Err(self.error(
                        path,
                        "Polygon shapes are 2D only; in 3D use Prism (a polygon extruded along an axis), CutBox or Box",
                    ));
                }
                Shape::Polygon(vertices.iter().map(|v| Vector2::new(v[0], v[1])).collect())
            }
            ShapeSpec::Prism { section, axis, from, to } => {
                if D != 3 {
                    return Err(self.error(path, "Prism shapes are 3D only; in 2D use Polygon"));
                }
                if from.partial_cmp(to) != Some(std::cmp::Ordering::Less) {
                    return Err(self.error(&at("to"), format!("Prism from {from} to {to}: `to` must exceed `from`")));
                }
                if section.len() < 3 || section.iter().flatten().any(|v| !v.is_finite()) {
                    return Err(self.error(&at("section"), "a Prism section needs at least 3 finite vertices"));
                }
                Shape::Prism {
                    section: section.iter().map(|v| Vector2::new(v[0], v[1])).collect(),
                    axis: axis.index(),
                    from: *from,
                    to: *to,
                }
            }
            ShapeSpec::CutBox { min, max, point, normal } => {
                let normal: nalgebra::SVector<f64, D> = self.vector(normal, &at("normal"), "CutBox normal")?;
                if normal.norm() == 0.0 {
                    return Err(self.error(&at("normal"), "a CutBox normal must not be zero"));
                }
                Shape::CutBox {
                    min: self.vector(min, &at("min"), "CutBox min")?,
                    max: self.vector(max, &at("max"), "CutBox max")?,
                    point: self.vector(point, &at("point"), "CutBox point")?,
                    normal,
                }
            }
        })
    }

    /// The initial velocities of an FEM model's Gauss points, each body's on its block.
    pub(super) fn fem_velocities<const D: usize>(&self, model: &mut Model<D>) -> Result<(), SceneError> {
        let mesh = model.background().mesh().expect("FEM model has a mesh");
        let per = mesh.gauss_per_element();
        let blocks: Vec<usize> = (0..model.points().len()).map(|p| mesh.element_block(p / per)).collect();
        let positions = model.points().position().to_vec();
        for (i, b) in self.scene.bodies.iter().enumerate() {
            if let Some(v) = &b.velocity {
                let field = self.velocity_field::<D>(v, i)?;
                for (p, velocity) in model.velocities_mut().iter_mut().enumerate().filter(|(p, _)| blocks[*p] == i) {
                    *velocity = field(&positions[p]);
                }
            }
        }
        Ok(())
    }

    /// The initial velocity field of body `i`.
    fn velocity_field<const D: usize>(
        &self,
        v: &VelocitySpec,
        i: usize,
    ) -> Result<impl Fn(&SVector<f64, D>) -> SVector<f64, D>, SceneError> {
        let at = [Seg::Key("bodies"), Seg::Index(i), Seg::Key("velocity")];
        let vec_d = |v: &[f64]| -> Result<SVector<f64, D>, SceneError> {
            if v.len() != D || v.iter().any(|x| !x.is_finite()) {
                return Err(self.error(&at, format!("body {i}: the velocity needs {D} finite components, got {v:?}")));
            }
            Ok(SVector::from_column_slice(v))
        };
        Ok(match v {
            VelocitySpec::Uniform(u) => {
                let u = vec_d(u)?;
                (u, 0usize, 0.0, 0.0)
            }
            VelocitySpec::Sine { amplitude, axis, wavelength, origin } => {
                let a = vec_d(amplitude)?;
                if axis.index() >= D {
                    return Err(
                        self.error(&at, format!("body {i}: the velocity's axis {axis:?} does not exist in {D}D"))
                    );
                }
                if !(wavelength.is_finite() && *wavelength > 0.0) {
                    return Err(
                        self.error(&at, format!("body {i}: the wavelength is {wavelength}; it must be positive"))
                    );
                }
                (a, axis.index(), 2.0 * std::f64::consts::PI / wavelength, *origin)
            }
        })
        .map(|(a, axis, k, origin)| {
            move |x: &SVector<f64, D>| if k == 0.0 { a } else { a * (k * (x[axis] - origin)).sin() }
        })
    }
}

/// The path of body `i`'s `key`.
/// The elements along each axis of the FEM reference's block from `min` to `max`: about
/// one grid cell each, at least one (as `f64`, so that a count too large for any mesh is
/// still a number).
pub(super) fn fem_elements<const D: usize>(min: &SVector<f64, D>, max: &SVector<f64, D>, grid: &Grid<D>) -> [f64; D] {
    std::array::from_fn(|a| ((max[a] - min[a]) / grid.cell_size()[a]).round().max(1.0))
}

fn body_key(i: usize, key: &'static str) -> [Seg<'static>; 3] {
    [Seg::Key("bodies"), Seg::Index(i), Seg::Key(key)]
}
