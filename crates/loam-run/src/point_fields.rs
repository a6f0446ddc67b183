//! The per-point fields a run writes — in every VTU frame and as the extra columns of
//! `points_final.csv` — chosen by the scene (`output.fields`): kinematics (displacement,
//! velocity), stress and its invariants p and q, volume, mass, material, the state of
//! the plastic laws (accumulated plastic strain, a yielding flag, every history value by
//! name), and with water the pore pressure and the total stress (the stress the laws see
//! is the effective one). A field that is off costs nothing.

use loam_format::output::{write_csv_table, write_vtu, OutputError, PointCloud, PvdWriter, VtuFormat};
use loam_model::Model;
use loam_scene::FieldSpec;
use nalgebra::{Matrix3, SVector};
use std::path::Path;

/// The fields a scene writes when it names none: everything the model has (the plastic
/// state only where some law is plastic).
pub(crate) fn default_fields<const D: usize>(model: &Model<D>) -> Vec<FieldSpec> {
    use FieldSpec::*;
    let mut fields = vec![Displacement, Velocity, Stress, MeanStress, DeviatoricStress, Volume, Mass, Material];
    if model.materials().iter().any(|m| m.history_len() > 0) {
        fields.extend([PlasticStrain, Yielding, History]);
    }
    if model.water().is_some() {
        fields.extend([PorePressure, TotalStress]);
    }
    fields
}

/// Named per-point values: scalars (one per point), vectors (D per point) and symmetric
/// tensors (xx, yy, zz, xy, yz, xz per point).
#[derive(Default)]
struct Fields {
    scalars: Vec<(String, Vec<f64>)>,
    vectors: Vec<(String, Vec<f64>)>,
    tensors: Vec<(String, Vec<f64>)>,
}

/// Mean stress p = −tr σ / 3 (compression positive, the geotechnical sign) and the von
/// Mises equivalent q = √(3/2 s:s).
fn invariants(s: &Matrix3<f64>) -> (f64, f64) {
    let p = -s.trace() / 3.0;
    let dev = s + Matrix3::identity() * p;
    (p, (1.5 * dev.norm_squared()).sqrt())
}

/// The six components (xx, yy, zz, xy, yz, xz) of every point's `stress(p)`.
fn tensor_field(n: usize, stress: impl Fn(usize) -> Matrix3<f64>) -> Vec<f64> {
    (0..n)
        .flat_map(|p| {
            let s = stress(p);
            [s[(0, 0)], s[(1, 1)], s[(2, 2)], s[(0, 1)], s[(1, 2)], s[(0, 2)]]
        })
        .collect()
}

/// `values` (`width` to a point, in the store's order) in the order `order`, the points'
/// id order ([`loam_points::PointStore::id_order`]; `None`: they are in it).
fn in_id_order(values: Vec<f64>, width: usize, order: Option<&[usize]>) -> Vec<f64> {
    match order {
        None => values,
        Some(order) => order.iter().flat_map(|&p| values[p * width..(p + 1) * width].iter().copied()).collect(),
    }
}

impl Fields {
    /// The `chosen` fields of `model`, pore pressures at gravity's factor `body_factor`,
    /// point by point in id order.
    fn of<const D: usize>(model: &Model<D>, chosen: &[FieldSpec], body_factor: f64) -> Self {
        let mut fields = Self::in_store_order(model, chosen, body_factor);
        let order = model.points().id_order();
        let order = order.as_deref();
        for (list, width) in [(&mut fields.scalars, 1), (&mut fields.vectors, D), (&mut fields.tensors, 6)] {
            for (_, values) in list.iter_mut() {
                *values = in_id_order(std::mem::take(values), width, order);
            }
        }
        fields
    }

    /// [`Fields::of`] in the order of the store.
    fn in_store_order<const D: usize>(model: &Model<D>, chosen: &[FieldSpec], body_factor: f64) -> Self {
        let pts = model.points();
        let flat = |v: &[SVector<f64, D>]| v.iter().flat_map(|x| x.iter().copied()).collect::<Vec<f64>>();
        let scalar = |f: &dyn Fn(usize) -> f64| (0..pts.len()).map(f).collect::<Vec<f64>>();
        let mut out = Fields::default();
        for field in chosen {
            match field {
                FieldSpec::Displacement => {
                    let u = pts.position().iter().zip(pts.position0()).map(|(x, x0)| x - x0).collect::<Vec<_>>();
                    out.vectors.push(("displacement".into(), flat(&u)));
                }
                FieldSpec::Velocity => out.vectors.push(("velocity".into(), flat(pts.velocity()))),
                FieldSpec::Stress => out.tensors.push(("stress".into(), tensor_field(pts.len(), |p| pts.stress()[p]))),
                FieldSpec::PorePressure => {
                    out.scalars.push(("pore_pressure".into(), scalar(&|p| model.pore_pressure(p, body_factor))))
                }
                FieldSpec::TotalStress => {
                    let total = |p| pts.stress()[p] - Matrix3::identity() * model.pore_pressure(p, body_factor);
                    out.tensors.push(("total_stress".into(), tensor_field(pts.len(), total)));
                }
                FieldSpec::MeanStress => out.scalars.push(("p".into(), scalar(&|p| invariants(&pts.stress()[p]).0))),
                FieldSpec::DeviatoricStress => {
                    out.scalars.push(("q".into(), scalar(&|p| invariants(&pts.stress()[p]).1)))
                }
                FieldSpec::Volume => out.scalars.push(("volume".into(), pts.volume().to_vec())),
                FieldSpec::Mass => out.scalars.push(("mass".into(), pts.mass().to_vec())),
                FieldSpec::Material => out.scalars.push(("material".into(), scalar(&|p| pts.material()[p] as f64))),
                FieldSpec::PlasticStrain => out.scalars.push((
                    "plastic_strain".into(),
                    scalar(&|p| model.law(p).plastic_strain(model.material_state(p).history)),
                )),
                FieldSpec::Yielding => {
                    out.scalars.push(("yielding".into(), scalar(&|p| f64::from(u8::from(yielding(model, p))))))
                }
                FieldSpec::History => out.scalars.extend(history_fields(model)),
            }
        }
        out
    }
}

/// Whether point `p` is on its law's yield surface, judged on the stress the law works
/// with (Kirchhoff τ = J σ in finite strain).
fn yielding<const D: usize>(model: &Model<D>, p: usize) -> bool {
    let state = model.material_state(p);
    model.law(p).is_yielding(&state.stress, state.history)
}

/// Every history value the laws name, one field per name (the union over the materials);
/// a point whose law lacks a name gets 0 there — an elastic body has no plastic strain —
/// not NaN, which the writers refuse as the sign of a run gone wrong.
fn history_fields<const D: usize>(model: &Model<D>) -> Vec<(String, Vec<f64>)> {
    let pts = model.points();
    let mut names: Vec<&'static str> = Vec::new();
    for m in model.materials() {
        for &n in m.history_names() {
            if !names.contains(&n) {
                names.push(n);
            }
        }
    }
    names
        .into_iter()
        .map(|name| {
            let values = (0..pts.len())
                .map(|p| {
                    let law = model.law(p);
                    law.history_names().iter().position(|&n| n == name).map_or(0.0, |k| pts.history(p)[k])
                })
                .collect();
            (name.to_string(), values)
        })
        .collect()
}

/// Write the frame of `step` (`points_<step>.vtu`, in `format`, beside the PVD file) with
/// the `chosen` fields (pore pressures at gravity's factor `body_factor`) and add it to the
/// PVD collection at `time`.
pub(crate) fn write_frame<const D: usize>(
    model: &Model<D>,
    chosen: &[FieldSpec],
    format: VtuFormat,
    body_factor: f64,
    pvd: &mut PvdWriter,
    step: usize,
    time: f64,
) -> Result<(), OutputError> {
    let f = Fields::of(model, chosen, body_factor);
    let positions: Vec<f64> = model.points().position().iter().flat_map(|x| x.iter().copied()).collect();
    let positions = in_id_order(positions, D, model.points().id_order().as_deref());
    let mut cloud = PointCloud::new(D, &positions);
    cloud.scalars = f.scalars.iter().map(|(n, v)| (n.as_str(), v.as_slice())).collect();
    cloud.vectors = f.vectors.iter().map(|(n, v)| (n.as_str(), v.as_slice())).collect();
    cloud.tensors = f.tensors.iter().map(|(n, v)| (n.as_str(), v.as_slice())).collect();
    let name = format!("points_{step:05}.vtu");
    let out_dir = pvd.path().parent().unwrap_or(Path::new("."));
    write_vtu(&out_dir.join(&name), &cloud, format)?;
    pvd.add(time, &name)
}

/// The stress columns of `points_final.csv` (and of the run log's monitors): name and
/// component, the in-plane ones and σ_zz in 2D, all six in 3D.
pub(crate) fn stress_columns(dim: usize) -> &'static [(&'static str, usize, usize)] {
    const ALL: [(&str, usize, usize); 6] =
        [("sxx", 0, 0), ("syy", 1, 1), ("szz", 2, 2), ("sxy", 0, 1), ("syz", 1, 2), ("sxz", 0, 2)];
    if dim == 3 {
        &ALL
    } else {
        &ALL[..4]
    }
}

/// `points_final.csv`: one row per point, in id order, with initial and current position, stress
/// (xx, yy, zz, xy[, yz, xz]), initial and current volume and mass, then the `chosen`
/// scalar fields beyond those (p, q, the plastic state, the pore pressure at gravity's
/// factor `body_factor`).
pub fn write_points_csv<const D: usize>(
    model: &Model<D>,
    chosen: &[FieldSpec],
    body_factor: f64,
    path: &Path,
) -> Result<(), OutputError> {
    let pts = &model.points();
    let axes = ["x", "y", "z"];
    let mut header: Vec<String> = Vec::new();
    let mut columns: Vec<Vec<f64>> = Vec::new();
    for a in 0..D {
        header.push(format!("{}0", axes[a]));
        columns.push(pts.position0().iter().map(|x| x[a]).collect());
    }
    for a in 0..D {
        header.push(axes[a].to_string());
        columns.push(pts.position().iter().map(|x| x[a]).collect());
    }
    for &(name, i, j) in stress_columns(D) {
        header.push(name.to_string());
        columns.push(pts.stress().iter().map(|s| s[(i, j)]).collect());
    }
    header.extend(["volume0", "volume", "mass"].map(String::from));
    columns.extend([pts.volume0().to_vec(), pts.volume().to_vec(), pts.mass().to_vec()]);
    let order = pts.id_order();
    for column in &mut columns {
        *column = in_id_order(std::mem::take(column), 1, order.as_deref());
    }
    use FieldSpec::*;
    let extra: Vec<FieldSpec> = (chosen.iter().copied())
        .filter(|f| {
            matches!(f, MeanStress | DeviatoricStress | Material | PlasticStrain | Yielding | History | PorePressure)
        })
        .collect();
    for (name, values) in Fields::of(model, &extra, body_factor).scalars {
        header.push(name);
        columns.push(values);
    }
    let header_refs: Vec<&str> = header.iter().map(|s| s.as_str()).collect();
    let column_refs: Vec<&[f64]> = columns.iter().map(|c| c.as_slice()).collect();
    write_csv_table(path, &header_refs, &column_refs)
}
