//! VTK XML UnstructuredGrid (`.vtu`) writer for point clouds.

use std::io::{self, Write};
use std::path::Path;

use super::{fmt_f64, write_atomic, xml_escape, OutputError, PointCloud};

/// VTK cell type of a single-point cell.
const VTK_VERTEX: u8 = 1;

/// Uncompressed size of a compressed block, as VTK's own writer uses.
const BLOCK_BYTES: usize = 32 * 1024;

/// The component names of a symmetric tensor array, in the order written.
const TENSOR_COMPONENTS: [&str; 6] = ["xx", "yy", "zz", "xy", "yz", "xz"];

/// How a VTU file stores its arrays.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum VtuFormat {
    /// Raw binary in the appended section, each array zlib-compressed in 32 KiB blocks
    /// (VTK's `vtkZLibDataCompressor`, read by ParaView 5 and VTK ≥ 6), the values as
    /// Float32: seven significant digits, enough to look at and plot, in half the bytes
    /// (the run's full-precision numbers are in `points_final.csv` and the logs).
    #[default]
    Binary,
    /// As `Binary`, the values as Float64.
    BinaryDouble,
    /// ASCII text, one point per line, every value to the digits that read back exactly:
    /// for reading by eye and diffing.
    Ascii,
}

/// Writes `cloud` as a VTK XML UnstructuredGrid, one `VTK_VERTEX` cell per point, in
/// `format` (which sets how the arrays are stored and the floats' precision).
///
/// Positions and vectors are padded with zeros to 3 components in 2D;
/// tensors are written as 6-component symmetric tensors (`XX, YY, ZZ, XY,
/// YZ, XZ`, named by `ComponentName` attributes). Shapes are validated first, then every
/// value is checked to be finite; nothing is written if either check fails. The file is
/// written to a temporary file in the same folder and renamed into place.
pub fn write_vtu(path: &Path, cloud: &PointCloud, format: VtuFormat) -> Result<(), OutputError> {
    cloud.validate()?;
    write_atomic(path, |w| match format {
        VtuFormat::Ascii => write_vtu_body(w, cloud, &mut AsciiArrays),
        VtuFormat::Binary => write_vtu_body(w, cloud, &mut AppendedArrays { data: Vec::new(), single: true }),
        VtuFormat::BinaryDouble => write_vtu_body(w, cloud, &mut AppendedArrays { data: Vec::new(), single: false }),
    })
}

/// The values of one data array.
enum ArrayData<'a> {
    /// `stride` values per point, padded with zeros to `pad_to`.
    Float { values: &'a [f64], stride: usize, pad_to: usize },
    /// `n` consecutive integers from `from` (the vertex cells' connectivity and offsets).
    Count { n: usize, from: i64 },
    /// `n` cell types, all `VTK_VERTEX`.
    Vertices { n: usize },
}

impl ArrayData<'_> {
    /// Whether every value has a finite single-precision form (beyond 3.4e38 a Float32
    /// would be infinite, so such an array is written in double precision).
    fn fits_single(&self) -> bool {
        match self {
            ArrayData::Float { values, .. } => values.iter().all(|v| v.abs() <= f32::MAX as f64),
            _ => true,
        }
    }

    /// The VTK type of the values, floats in `single` precision or double.
    fn vtk_type(&self, single: bool) -> &'static str {
        match self {
            ArrayData::Float { .. } if single => "Float32",
            ArrayData::Float { .. } => "Float64",
            ArrayData::Count { .. } => "Int64",
            ArrayData::Vertices { .. } => "UInt8",
        }
    }

    /// The values as little-endian bytes, floats in `single` precision or double.
    fn bytes(&self, single: bool) -> Vec<u8> {
        match *self {
            ArrayData::Float { values, stride, pad_to } => {
                let padded = values
                    .chunks(stride)
                    .flat_map(|point| (0..pad_to).map(move |k| point.get(k).copied().unwrap_or(0.0)));
                if single {
                    padded.flat_map(|v| (v as f32).to_le_bytes()).collect()
                } else {
                    padded.flat_map(f64::to_le_bytes).collect()
                }
            }
            ArrayData::Count { n, from } => (from..from + n as i64).flat_map(i64::to_le_bytes).collect(),
            ArrayData::Vertices { n } => vec![VTK_VERTEX; n],
        }
    }
}

/// Where the arrays' values go: inline as text, or into the appended section.
trait ArrayWriter {
    /// The `VTKFile` attribute naming the compressor, if any.
    fn compressor(&self) -> &'static str;
    /// Whether floats are written in single precision where they fit.
    fn single(&self) -> bool;
    /// The attributes that close a `DataArray` start tag and, inline, its values and end
    /// tag, floats in `single` precision or double.
    fn array(&mut self, w: &mut dyn Write, data: &ArrayData, single: bool) -> io::Result<()>;
    /// What follows the XML tree, to the end of the file.
    fn finish(&mut self, w: &mut dyn Write) -> io::Result<()>;
}

struct AsciiArrays;

impl ArrayWriter for AsciiArrays {
    fn compressor(&self) -> &'static str {
        ""
    }

    fn single(&self) -> bool {
        false
    }

    fn finish(&mut self, w: &mut dyn Write) -> io::Result<()> {
        writeln!(w, "</VTKFile>")
    }

    fn array(&mut self, w: &mut dyn Write, data: &ArrayData, _single: bool) -> io::Result<()> {
        writeln!(w, r#" format="ascii">"#)?;
        match *data {
            ArrayData::Float { values, stride, pad_to } => {
                for point in values.chunks(stride) {
                    write!(w, "         ")?;
                    for k in 0..pad_to {
                        write!(w, " {}", fmt_f64(point.get(k).copied().unwrap_or(0.0)))?;
                    }
                    writeln!(w)?;
                }
            }
            ArrayData::Count { n, from } => int_lines(w, (from..from + n as i64).map(|i| i.to_string()))?,
            ArrayData::Vertices { n } => int_lines(w, (0..n).map(|_| VTK_VERTEX.to_string()))?,
        }
        writeln!(w, "        </DataArray>")
    }
}

/// The compressed arrays of the appended section, in the order their tags were written.
struct AppendedArrays {
    data: Vec<u8>,
    /// Floats as Float32.
    single: bool,
}

impl ArrayWriter for AppendedArrays {
    fn compressor(&self) -> &'static str {
        r#" compressor="vtkZLibDataCompressor""#
    }

    fn single(&self) -> bool {
        self.single
    }

    fn array(&mut self, w: &mut dyn Write, data: &ArrayData, single: bool) -> io::Result<()> {
        writeln!(w, r#" format="appended" offset="{}"/>"#, self.data.len())?;
        compress_blocks(&data.bytes(single), &mut self.data)
    }

    /// The appended section after the XML tree, and the file's end.
    fn finish(&mut self, w: &mut dyn Write) -> io::Result<()> {
        write!(w, "  <AppendedData encoding=\"raw\">\n   _")?;
        w.write_all(&self.data)?;
        writeln!(w, "\n  </AppendedData>")?;
        writeln!(w, "</VTKFile>")
    }
}

/// `raw` zlib-compressed in blocks of `BLOCK_BYTES`, with VTK's header in front (UInt64:
/// the number of blocks, the block size, the size of a partial last block or 0, then each
/// block's compressed size), appended to `out`.
fn compress_blocks(raw: &[u8], out: &mut Vec<u8>) -> io::Result<()> {
    let blocks: Vec<Vec<u8>> = raw
        .chunks(BLOCK_BYTES)
        .map(|block| {
            let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
            z.write_all(block)?;
            z.finish()
        })
        .collect::<io::Result<_>>()?;
    let partial = raw.len() % BLOCK_BYTES;
    let header = [blocks.len(), BLOCK_BYTES, partial].into_iter().chain(blocks.iter().map(Vec::len));
    out.extend(header.flat_map(|v| (v as u64).to_le_bytes()));
    blocks.iter().for_each(|b| out.extend_from_slice(b));
    Ok(())
}

fn write_vtu_body(w: &mut dyn Write, c: &PointCloud, arrays: &mut dyn ArrayWriter) -> io::Result<()> {
    let n = c.len();
    let dim = c.dim;
    writeln!(w, r#"<?xml version="1.0"?>"#)?;
    let compressor = arrays.compressor();
    writeln!(
        w,
        r#"<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64"{compressor}>"#
    )?;
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
        data_array(w, arrays, name, 1, &[], &ArrayData::Float { values: v, stride: 1, pad_to: 1 })?;
    }
    for (name, v) in &c.vectors {
        data_array(w, arrays, name, 3, &[], &ArrayData::Float { values: v, stride: dim, pad_to: 3 })?;
    }
    for (name, v) in &c.tensors {
        data_array(w, arrays, name, 6, &TENSOR_COMPONENTS, &ArrayData::Float { values: v, stride: 6, pad_to: 6 })?;
    }
    writeln!(w, "      </PointData>")?;

    writeln!(w, "      <Points>")?;
    data_array(w, arrays, "Points", 3, &[], &ArrayData::Float { values: c.positions, stride: dim, pad_to: 3 })?;
    writeln!(w, "      </Points>")?;

    writeln!(w, "      <Cells>")?;
    data_array(w, arrays, "connectivity", 1, &[], &ArrayData::Count { n, from: 0 })?;
    data_array(w, arrays, "offsets", 1, &[], &ArrayData::Count { n, from: 1 })?;
    data_array(w, arrays, "types", 1, &[], &ArrayData::Vertices { n })?;
    writeln!(w, "      </Cells>")?;

    writeln!(w, "    </Piece>")?;
    writeln!(w, "  </UnstructuredGrid>")?;
    arrays.finish(w)
}

/// Writes one `DataArray`'s start tag with `comps` components (named by `names`, if
/// any), then hands its values to `arrays`.
fn data_array(
    w: &mut dyn Write,
    arrays: &mut dyn ArrayWriter,
    name: &str,
    comps: usize,
    names: &[&str],
    data: &ArrayData,
) -> io::Result<()> {
    let single = arrays.single() && data.fits_single();
    write!(w, r#"        <DataArray type="{}" Name="{}""#, data.vtk_type(single), xml_escape(name))?;
    if comps > 1 {
        write!(w, r#" NumberOfComponents="{comps}""#)?;
    }
    for (k, component) in names.iter().enumerate() {
        write!(w, r#" ComponentName{k}="{component}""#)?;
    }
    arrays.array(w, data, single)
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
        write_vtu(&p, cloud, VtuFormat::Ascii).unwrap();
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

    /// Reads a binary frame back as VTK's reader does: the XML tree up to the appended
    /// section (parsed by roxmltree), each array at its offset after the `_`, its UInt64
    /// block header, the zlib blocks inflated. Returns (name, type, component names, bytes).
    fn read_binary(bytes: &[u8]) -> Vec<(String, String, Vec<String>, Vec<u8>)> {
        use std::io::Read;
        let marker = b"<AppendedData encoding=\"raw\">";
        let at = bytes.windows(marker.len()).position(|w| w == marker).expect("an appended section");
        let underscore = at + bytes[at..].iter().position(|&b| b == b'_').unwrap() + 1;
        let xml = format!("{}</VTKFile>", std::str::from_utf8(&bytes[..at]).unwrap());
        let doc = roxmltree::Document::parse(&xml).unwrap();
        let root = doc.root_element();
        assert_eq!(root.attribute("compressor"), Some("vtkZLibDataCompressor"));
        assert_eq!(root.attribute("header_type"), Some("UInt64"));
        let word = |at: usize| u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap()) as usize;
        doc.descendants()
            .filter(|n| n.has_tag_name("DataArray"))
            .map(|n| {
                assert_eq!(n.attribute("format"), Some("appended"));
                let start = underscore + n.attribute("offset").unwrap().parse::<usize>().unwrap();
                let (blocks, block, partial) = (word(start), word(start + 8), word(start + 16));
                let mut data = start + 24 + 8 * blocks;
                let mut raw = Vec::new();
                for b in 0..blocks {
                    let size = word(start + 24 + 8 * b);
                    let mut inflated = Vec::new();
                    flate2::read::ZlibDecoder::new(&bytes[data..data + size]).read_to_end(&mut inflated).unwrap();
                    let expected = if b + 1 == blocks && partial > 0 { partial } else { block };
                    assert_eq!(inflated.len(), expected);
                    raw.extend(inflated);
                    data += size;
                }
                let names = (0..6).filter_map(|k| n.attribute(format!("ComponentName{k}").as_str()).map(String::from));
                (
                    n.attribute("Name").unwrap().to_string(),
                    n.attribute("type").unwrap().to_string(),
                    names.collect(),
                    raw,
                )
            })
            .collect()
    }

    /// The double-precision binary frame holds the very values of the ASCII one, bit for
    /// bit (the single-precision one their f32 roundings), in arrays that
    /// span several 32 KiB blocks (5000 points × 6 × 8 bytes of stress = 7 blocks, the last
    /// partial), with component names on the tensor; the cells are vertices 0..n.
    #[test]
    fn binary_frames_hold_the_values_bit_for_bit() {
        let n = 5000;
        let pos: Vec<f64> = (0..2 * n).map(|i| (i as f64).sin() * 1e3).collect();
        let stress: Vec<f64> = (0..6 * n).map(|i| (i as f64 * 0.37).cos() * 1e5 + 1e-300).collect();
        let mass: Vec<f64> = (0..n).map(|i| 1.0 + i as f64 / 7.0).collect();
        let cloud = PointCloud::new(2, &pos).with_scalar("mass", &mass).with_tensor("stress", &stress);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("cloud.vtu");
        write_vtu(&path, &cloud, VtuFormat::BinaryDouble).unwrap();
        let arrays = read_binary(&fs::read(&path).unwrap());
        let floats = |b: &[u8]| b.chunks(8).map(|c| f64::from_le_bytes(c.try_into().unwrap())).collect::<Vec<_>>();
        let ints = |b: &[u8]| b.chunks(8).map(|c| i64::from_le_bytes(c.try_into().unwrap())).collect::<Vec<_>>();
        let names: Vec<&str> = arrays.iter().map(|a| a.0.as_str()).collect();
        assert_eq!(names, ["mass", "stress", "Points", "connectivity", "offsets", "types"]);
        assert_eq!(floats(&arrays[0].3), mass);
        assert_eq!(floats(&arrays[1].3), stress);
        assert_eq!(arrays[1].2, ["xx", "yy", "zz", "xy", "yz", "xz"]);
        let padded: Vec<f64> = pos.chunks(2).flat_map(|p| [p[0], p[1], 0.0]).collect();
        assert_eq!(floats(&arrays[2].3), padded);
        assert_eq!(ints(&arrays[3].3), (0..n as i64).collect::<Vec<_>>());
        assert_eq!(ints(&arrays[4].3), (1..=n as i64).collect::<Vec<_>>());
        assert_eq!((arrays[5].1.as_str(), arrays[5].3.clone()), ("UInt8", vec![VTK_VERTEX; n]));
        // Single precision: each value rounded to the nearest f32, nothing else changed.
        write_vtu(&path, &cloud, VtuFormat::Binary).unwrap();
        let arrays = read_binary(&fs::read(&path).unwrap());
        let singles = |b: &[u8]| b.chunks(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect::<Vec<_>>();
        assert_eq!(arrays[1].1, "Float32");
        assert_eq!(singles(&arrays[1].3), stress.iter().map(|&v| v as f32).collect::<Vec<_>>());
        assert_eq!(ints(&arrays[4].3), (1..=n as i64).collect::<Vec<_>>());
        // A value beyond f32's range keeps its array in double precision, not infinite.
        let huge = [1e39, 1.0];
        write_vtu(&path, &PointCloud::new(2, &[0.0, 0.0, 1.0, 1.0]).with_scalar("q", &huge), VtuFormat::Binary)
            .unwrap();
        let arrays = read_binary(&fs::read(&path).unwrap());
        assert_eq!((arrays[0].1.as_str(), floats(&arrays[0].3)), ("Float64", huge.to_vec()));
        assert_eq!(arrays[1].1, "Float32");
        // An empty cloud is a valid file too: every array zero blocks.
        write_vtu(&path, &PointCloud::new(3, &[]), VtuFormat::Binary).unwrap();
        assert!(read_binary(&fs::read(&path).unwrap()).iter().all(|a| a.3.is_empty()));
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
        let err = write_vtu(&p, &PointCloud::new(2, &pos).with_scalar("mass", &short), VtuFormat::Ascii).unwrap_err();
        match err {
            OutputError::Shape { field, expected, found } => {
                assert_eq!(field, "mass");
                assert_eq!(expected, 2);
                assert_eq!(found, 1);
            }
            e => panic!("unexpected {e:?}"),
        }
        let t = [0.0; 11];
        let err = write_vtu(&p, &PointCloud::new(2, &pos).with_tensor("stress", &t), VtuFormat::Ascii).unwrap_err();
        assert!(matches!(
            err,
            OutputError::Shape { ref field, expected: 12, found: 11 } if field == "stress"
        ));
        // Ragged positions.
        let err = write_vtu(&p, &PointCloud::new(3, &pos), VtuFormat::Ascii).unwrap_err();
        assert!(matches!(
            err,
            OutputError::Shape { ref field, expected: 3, found: 4 } if field == "positions"
        ));
        let err = write_vtu(&p, &PointCloud::new(1, &pos), VtuFormat::Ascii).unwrap_err();
        assert!(matches!(err, OutputError::Dim { found: 1 }));
        assert!(!p.exists());
    }

    #[test]
    fn vtu_refuses_nan_and_inf() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bad.vtu");
        let pos = [0.0, 0.0, 1.0, 1.0, 2.0, 2.0];
        let v = [0.0, 0.0, 0.0, 0.0, 1.0, f64::NAN];
        let err = write_vtu(&p, &PointCloud::new(2, &pos).with_vector("velocity", &v), VtuFormat::Ascii).unwrap_err();
        match &err {
            OutputError::NonFinite { field, point } => {
                assert_eq!(field, "velocity");
                assert_eq!(*point, 2);
            }
            e => panic!("unexpected {e:?}"),
        }
        assert!(err.to_string().contains("velocity"));
        let s = [0.0, f64::INFINITY, 0.0];
        let err = write_vtu(&p, &PointCloud::new(2, &pos).with_scalar("p", &s), VtuFormat::Ascii).unwrap_err();
        assert!(matches!(err, OutputError::NonFinite { ref field, point: 1 } if field == "p"));
        let bad_pos = [0.0, 0.0, 1.0, f64::NEG_INFINITY];
        let err = write_vtu(&p, &PointCloud::new(2, &bad_pos), VtuFormat::Ascii).unwrap_err();
        assert!(matches!(err, OutputError::NonFinite { ref field, point: 1 } if field == "positions"));
        assert!(!p.exists());
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn vtu_shape_checked_before_finiteness() {
        let dir = tempfile::tempdir().unwrap();
        let pos = [f64::NAN, 0.0];
        let s = [1.0, 2.0];
        let err =
            write_vtu(&dir.path().join("x.vtu"), &PointCloud::new(2, &pos).with_scalar("s", &s), VtuFormat::Ascii)
                .unwrap_err();
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
