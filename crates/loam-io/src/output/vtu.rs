//! VTK XML UnstructuredGrid (`.vtu`) writer for point clouds.

use std::io::{self, Write};
use std::path::Path;

use super::{fmt_f64, write_atomic, xml_escape, OutputError, PointCloud};

/// VTK cell type of a single-point cell.
const VTK_VERTEX: u8 = 1;

/// Writes `cloud` as a VTK XML UnstructuredGrid, one `VTK_VERTEX` cell per
/// point, ASCII Float64 data.
///
/// Positions and vectors are padded with zeros to 3 components in 2D;
/// tensors are written as 6-component symmetric tensors (`XX, YY, ZZ, XY,
/// YZ, XZ`). Shapes are validated first, then every value is checked to be
/// finite; nothing is written if either check fails. The file is written to
/// a temporary file in the same folder and renamed into place.
pub fn write_vtu(path: &Path, cloud: &PointCloud) -> Result<(), OutputError> {
    cloud.validate()?;
    write_atomic(path, |w| write_vtu_body(w, cloud))
}

fn write_vtu_body(w: &mut dyn Write, c: &PointCloud) -> io::Result<()> {
    let n = c.len();
    let dim = c.dim;
    writeln!(w, r#"<?xml version="1.0"?>"#)?;
    writeln!(w, r#"<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64">"#)?;
    writeln!(w, "  <UnstructuredGrid>")?;
    writeln!(w, r#"    <Piece NumberOfPoints="{n}" NumberOfCells="{n}">"#)?;

    // Point data, with the first field of each kind marked active.
    let mut active = String::new();
    for (attr, fields) in [("Scalars", &c.scalars), ("Vectors", &c.vectors), ("Tensors", &c.tensors)] {
        if let Some((name, _)) = fields.first() {
            active.push_str(&format!(r#" {attr}="{}""#, xml_escape(name)));
        }
    }
    writeln!(w, "      <PointData{active}>")?;
    for (name, v) in &c.scalars {
        data_array(w, name, 1, v, 1, 1)?;
    }
    for (name, v) in &c.vectors {
        data_array(w, name, 3, v, dim, 3)?;
    }
    for (name, v) in &c.tensors {
        data_array(w, name, 6, v, 6, 6)?;
    }
    writeln!(w, "      </PointData>")?;

    writeln!(w, "      <Points>")?;
    data_array(w, "Points", 3, c.positions, dim, 3)?;
    writeln!(w, "      </Points>")?;

    writeln!(w, "      <Cells>")?;
    writeln!(w, r#"        <DataArray type="Int64" Name="connectivity" format="ascii">"#)?;
    int_lines(w, (0..n).map(|i| i.to_string()))?;
    writeln!(w, "        </DataArray>")?;
    writeln!(w, r#"        <DataArray type="Int64" Name="offsets" format="ascii">"#)?;
    int_lines(w, (1..=n).map(|i| i.to_string()))?;
    writeln!(w, "        </DataArray>")?;
    writeln!(w, r#"        <DataArray type="UInt8" Name="types" format="ascii">"#)?;
    int_lines(w, (0..n).map(|_| VTK_VERTEX.to_string()))?;
    writeln!(w, "        </DataArray>")?;
    writeln!(w, "      </Cells>")?;

    writeln!(w, "    </Piece>")?;
    writeln!(w, "  </UnstructuredGrid>")?;
    writeln!(w, "</VTKFile>")?;
    Ok(())
}

/// Writes one Float64 `DataArray`, one point per line. `stride` values per
/// point are read from `values` and padded with zeros to `comps`.
fn data_array(
    w: &mut dyn Write,
    name: &str,
    comps: usize,
    values: &[f64],
    stride: usize,
    pad_to: usize,
) -> io::Result<()> {
    write!(w, r#"        <DataArray type="Float64" Name="{}""#, xml_escape(name))?;
    if comps > 1 {
        write!(w, r#" NumberOfComponents="{comps}""#)?;
    }
    writeln!(w, r#" format="ascii">"#)?;
    for point in values.chunks(stride) {
        write!(w, "         ")?;
        for k in 0..pad_to {
            let v = point.get(k).copied().unwrap_or(0.0);
            write!(w, " {}", fmt_f64(v))?;
        }
        writeln!(w)?;
    }
    writeln!(w, "        </DataArray>")
}

/// Writes integers, up to 16 per line.
fn int_lines(w: &mut dyn Write, items: impl Iterator<Item = String>) -> io::Result<()> {
    let items: Vec<String> = items.collect();
    for line in items.chunks(16) {
        writeln!(w, "          {}", line.join(" "))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    fn write_and_read(cloud: &PointCloud) -> String {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("cloud.vtu");
        write_vtu(&p, cloud).unwrap();
        fs::read_to_string(p).unwrap()
    }

    #[test]
    fn vtu_2d_snapshot() {
        let pos = [0.0, 0.0, 1.0, 0.5, 0.25, 2.0];
        let p = [1.5, -2.0, 1e-9];
        let v = [1.0, 0.0, 0.0, -1.0, 0.1, 0.2];
        let s = [
            -1.0, -2.0, -3.0, 0.5, 0.0, 0.0, //
            -1.1, -2.1, -3.1, 0.6, 0.0, 0.0, //
            -1.2, -2.2, -3.2, 0.7, 0.0, 0.0,
        ];
        let cloud =
            PointCloud::new(2, &pos).with_scalar("pressure", &p).with_vector("velocity", &v).with_tensor("stress", &s);
        insta::assert_snapshot!(write_and_read(&cloud));
    }

    #[test]
    fn vtu_3d_snapshot() {
        let pos = [0.0, 0.0, 0.0, 1.0, 2.0, 3.0];
        let mass = [0.125, 2.0];
        let j = [1.0, 0.98];
        let u = [0.0, 0.0, -1e-3, 0.5, 0.25, 0.125];
        let cloud = PointCloud {
            dim: 3,
            positions: &pos,
            scalars: vec![("mass", &mass), ("J", &j)],
            vectors: vec![("displacement", &u)],
            tensors: vec![],
        };
        insta::assert_snapshot!(write_and_read(&cloud));
    }

    #[test]
    fn vtu_empty_cloud_is_valid() {
        let cloud = PointCloud::new(3, &[]);
        let s = write_and_read(&cloud);
        assert!(s.contains(r#"NumberOfPoints="0""#));
        assert!(s.trim_end().ends_with("</VTKFile>"));
    }

    #[test]
    fn vtu_structure_counts() {
        let pos: Vec<f64> = (0..40).map(|i| i as f64 * 0.5).collect();
        let s = write_and_read(&PointCloud::new(2, &pos));
        assert!(s.contains(r#"NumberOfPoints="20" NumberOfCells="20""#));
        let types = s.split(r#"Name="types" format="ascii">"#).nth(1).unwrap();
        let types = types.split("</DataArray>").next().unwrap();
        assert_eq!(types.split_whitespace().filter(|t| *t == "1").count(), 20);
        let offsets = s.split(r#"Name="offsets" format="ascii">"#).nth(1).unwrap();
        let last = offsets.split("</DataArray>").next().unwrap();
        assert_eq!(last.split_whitespace().last(), Some("20"));
    }

    #[test]
    fn vtu_shape_mismatch_names_field() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bad.vtu");
        let pos = [0.0, 0.0, 1.0, 1.0];
        let short = [1.0];
        let err = write_vtu(&p, &PointCloud::new(2, &pos).with_scalar("mass", &short)).unwrap_err();
        match err {
            OutputError::Shape { field, expected, found } => {
                assert_eq!(field, "mass");
                assert_eq!(expected, 2);
                assert_eq!(found, 1);
            }
            e => panic!("unexpected {e:?}"),
        }
        let t = [0.0; 11];
        let err = write_vtu(&p, &PointCloud::new(2, &pos).with_tensor("stress", &t)).unwrap_err();
        assert!(matches!(
            err,
            OutputError::Shape { ref field, expected: 12, found: 11 } if field == "stress"
        ));
        // Ragged positions.
        let err = write_vtu(&p, &PointCloud::new(3, &pos)).unwrap_err();
        assert!(matches!(
            err,
            OutputError::Shape { ref field, expected: 3, found: 4 } if field == "positions"
        ));
        let err = write_vtu(&p, &PointCloud::new(1, &pos)).unwrap_err();
        assert!(matches!(err, OutputError::Dim { found: 1 }));
        assert!(!p.exists());
    }

    #[test]
    fn vtu_refuses_nan_and_inf() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bad.vtu");
        let pos = [0.0, 0.0, 1.0, 1.0, 2.0, 2.0];
        let v = [0.0, 0.0, 0.0, 0.0, 1.0, f64::NAN];
        let err = write_vtu(&p, &PointCloud::new(2, &pos).with_vector("velocity", &v)).unwrap_err();
        match &err {
            OutputError::NonFinite { field, point } => {
                assert_eq!(field, "velocity");
                assert_eq!(*point, 2);
            }
            e => panic!("unexpected {e:?}"),
        }
        assert!(err.to_string().contains("velocity"));
        let s = [0.0, f64::INFINITY, 0.0];
        let err = write_vtu(&p, &PointCloud::new(2, &pos).with_scalar("p", &s)).unwrap_err();
        assert!(matches!(err, OutputError::NonFinite { ref field, point: 1 } if field == "p"));
        let bad_pos = [0.0, 0.0, 1.0, f64::NEG_INFINITY];
        let err = write_vtu(&p, &PointCloud::new(2, &bad_pos)).unwrap_err();
        assert!(matches!(err, OutputError::NonFinite { ref field, point: 1 } if field == "positions"));
        assert!(!p.exists());
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn vtu_shape_checked_before_finiteness() {
        let dir = tempfile::tempdir().unwrap();
        let pos = [f64::NAN, 0.0];
        let s = [1.0, 2.0];
        let err = write_vtu(&dir.path().join("x.vtu"), &PointCloud::new(2, &pos).with_scalar("s", &s)).unwrap_err();
        assert!(matches!(err, OutputError::Shape { .. }));
    }

    #[test]
    fn vtu_escapes_field_names() {
        let pos = [0.0, 0.0];
        let s = [1.0];
        let out = write_and_read(&PointCloud::new(2, &pos).with_scalar("a<b&\"c\"", &s));
        assert!(out.contains(r#"Name="a&lt;b&amp;&quot;c&quot;""#));
    }
}
