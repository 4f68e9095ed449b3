//! The summary table of a batch: `summary.csv` and `summary.parquet` in the output
//! folder, one row per shape, sorted by name, with the same columns (see [`COLUMNS`]).
//!
//! Lists (outputs, warnings) are joined into one text cell: outputs by `;`, warnings by
//! ` | `. Empty cells (CSV) and nulls (Parquet) stand for unknown values. The CSV quotes a
//! cell with a comma, a quote or a line break (RFC 4180). Parquet is written by the
//! `parquet` crate (no compression, one row group): pandas, polars, DuckDB and Arrow read
//! it.

use std::path::Path;
use std::sync::Arc;

use parquet::data_type::{BoolType, ByteArray, ByteArrayType, DataType, DoubleType, Int64Type};
use parquet::file::properties::WriterProperties;
use parquet::file::writer::{SerializedColumnWriter, SerializedFileWriter};
use parquet::schema::parser::parse_message_type;

use super::BatchError;
use super::record::BatchRecord;
use crate::io::write_atomic_durable;

/// The columns of the summary, in order.
pub const COLUMNS: [&str; 18] = [
    "name",
    "input",
    "status",
    "reused",
    "error",
    "kind",
    "n",
    "faces",
    "components",
    "k",
    "discretization",
    "seconds",
    "peak_memory_bytes",
    "max_residual",
    "outputs",
    "input_hash",
    "params_hash",
    "warnings",
];

const SCHEMA: &str = "message batch_summary {
  required binary name (STRING);
  required binary input (STRING);
  required binary status (STRING);
  required boolean reused;
  optional binary error (STRING);
  optional binary kind (STRING);
  optional int64 n;
  optional int64 faces;
  optional int64 components;
  optional int64 k;
  required binary discretization (STRING);
  required double seconds;
  optional int64 peak_memory_bytes;
  optional double max_residual;
  required binary outputs (STRING);
  optional binary input_hash (STRING);
  required binary params_hash (STRING);
  required binary warnings (STRING);
}";

/// One cell of a row.
enum Cell {
    Text(Option<String>),
    Int(Option<i64>),
    Float(Option<f64>),
    Bool(bool),
}

fn cells(r: &BatchRecord) -> Vec<Cell> {
    let int = |v: Option<usize>| Cell::Int(v.map(|x| x as i64));
    vec![
        Cell::Text(Some(r.name.clone())),
        Cell::Text(Some(r.input.clone())),
        Cell::Text(Some(r.status.to_string())),
        Cell::Bool(r.reused),
        Cell::Text(r.error.clone()),
        Cell::Text(r.shape.kind.map(|k| k.to_string())),
        int(r.shape.n),
        int(r.shape.faces),
        int(r.shape.components),
        int(r.basis.k),
        Cell::Text(Some(r.basis.discretization.clone())),
        Cell::Float(Some(r.seconds)),
        Cell::Int(r.peak_memory_bytes.map(|b| b as i64)),
        Cell::Float(r.basis.max_residual),
        Cell::Text(Some(r.outputs.join(";"))),
        Cell::Text(r.input_hash.clone()),
        Cell::Text(Some(r.params_hash.clone())),
        Cell::Text(Some(r.warnings.join(" | "))),
    ]
}

pub(crate) fn csv_cell(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The summary as CSV text (a header line, then one line per record, in the given order).
pub fn summary_csv(records: &[BatchRecord]) -> String {
    let mut s = COLUMNS.join(",");
    s.push('\n');
    for r in records {
        let line: Vec<String> = cells(r)
            .into_iter()
            .map(|c| match c {
                Cell::Text(t) => csv_cell(t.as_deref().unwrap_or("")),
                Cell::Int(v) => v.map(|x| x.to_string()).unwrap_or_default(),
                Cell::Float(v) => v.map(|x| format!("{x:?}")).unwrap_or_default(),
                Cell::Bool(b) => b.to_string(),
            })
            .collect();
        s.push_str(&line.join(","));
        s.push('\n');
    }
    s
}

/// Writes an optional column of Parquet type `T`: the present values and the definition
/// levels (1 present, 0 null), `value` giving each cell's value.
fn write_optional<'a, T: DataType>(
    col: &mut SerializedColumnWriter<'_>,
    column: impl Iterator<Item = &'a Cell>,
    value: impl Fn(&'a Cell) -> Option<T::T>,
) -> Result<(), parquet::errors::ParquetError> {
    let mut values = Vec::new();
    let mut defs = Vec::new();
    for cell in column {
        let v = value(cell);
        defs.push(i16::from(v.is_some()));
        values.extend(v);
    }
    col.typed::<T>().write_batch(&values, Some(&defs), None)?;
    Ok(())
}

/// The summary as a Parquet file in memory.
pub fn summary_parquet(records: &[BatchRecord]) -> Result<Vec<u8>, parquet::errors::ParquetError> {
    let schema = Arc::new(parse_message_type(SCHEMA)?);
    let props = Arc::new(
        WriterProperties::builder()
            .set_created_by(format!("spectral-mesh {}", env!("CARGO_PKG_VERSION")))
            .build(),
    );
    let rows: Vec<Vec<Cell>> = records.iter().map(cells).collect();
    let mut buf = Vec::new();
    let mut writer = SerializedFileWriter::new(&mut buf, schema, props)?;
    let mut group = writer.next_row_group()?;
    let mut c = 0;
    while let Some(mut col) = group.next_column()? {
        let column = rows.iter().map(|r| &r[c]);
        match rows.first().map(|r| &r[c]) {
            // No rows: every column is empty, whatever its type.
            None => {}
            Some(Cell::Text(_)) => {
                write_optional::<ByteArrayType>(&mut col, column, |c| match c {
                    Cell::Text(Some(t)) => Some(ByteArray::from(t.as_bytes().to_vec())),
                    _ => None,
                })?
            }
            Some(Cell::Int(_)) => write_optional::<Int64Type>(&mut col, column, |c| match c {
                Cell::Int(v) => *v,
                _ => None,
            })?,
            Some(Cell::Float(_)) => write_optional::<DoubleType>(&mut col, column, |c| match c {
                Cell::Float(v) => *v,
                _ => None,
            })?,
            Some(Cell::Bool(_)) => {
                let values: Vec<bool> = column
                    .map(|cell| matches!(cell, Cell::Bool(true)))
                    .collect();
                col.typed::<BoolType>().write_batch(&values, None, None)?;
            }
        }
        col.close()?;
        c += 1;
    }
    group.close()?;
    writer.close()?;
    Ok(buf)
}

/// Writes `out/summary.csv` and `out/summary.parquet` (each atomically), the records
/// sorted by name. Returns the two paths.
pub fn write_summary(
    out: &Path,
    records: &[BatchRecord],
) -> Result<[std::path::PathBuf; 2], BatchError> {
    let mut sorted = records.to_vec();
    sorted.sort_by(|a, b| a.name.cmp(&b.name));
    let csv = out.join("summary.csv");
    let pq = out.join("summary.parquet");
    write_atomic_durable(&csv, summary_csv(&sorted).as_bytes())
        .map_err(|e| BatchError::Write(e.to_string()))?;
    let bytes = summary_parquet(&sorted)
        .map_err(|e| BatchError::Write(format!("{}: {e}", pq.display())))?;
    write_atomic_durable(&pq, &bytes).map_err(|e| BatchError::Write(e.to_string()))?;
    Ok([csv, pq])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::batch::record::{BasisSummary, InputKind, ShapeCounts, Status};

    fn rows() -> Vec<BatchRecord> {
        let mut a = BatchRecord::new("a.off", "/data/a.off", "p");
        a.status = Status::Ok;
        a.shape = ShapeCounts {
            kind: Some(InputKind::Mesh),
            n: Some(10),
            faces: Some(16),
            components: Some(1),
        };
        a.basis = BasisSummary {
            k: Some(5),
            discretization: "fem".into(),
            max_residual: Some(1e-12),
        };
        a.seconds = 0.25;
        a.outputs = vec!["a.off.png".into(), "a.off.npz".into()];
        a.input_hash = Some("h".into());
        let b = BatchRecord::failed("b,\"x\".off", "b.off", "p", "b.off:3: line\nbroken");
        vec![a, b]
    }

    #[test]
    fn csv_quotes_and_leaves_unknowns_empty() {
        let s = summary_csv(&rows());
        let lines: Vec<&str> = s.lines().collect();
        assert_eq!(lines[0], COLUMNS.join(","));
        assert_eq!(
            lines[1],
            "a.off,/data/a.off,ok,false,,mesh,10,16,1,5,fem,0.25,,1e-12,a.off.png;a.off.npz,h,p,"
        );
        assert!(
            s.contains(
                "\"b,\"\"x\"\".off\",b.off,failed,false,\"b.off:3: line\nbroken\",,,,,,,0.0,"
            ),
            "{s}"
        );
    }

    #[test]
    fn parquet_is_a_parquet_file_with_every_row() {
        use parquet::file::reader::{FileReader, SerializedFileReader};
        let dir = tempfile::tempdir().unwrap();
        let [_, pq] = write_summary(dir.path(), &rows()).unwrap();
        let bytes = std::fs::read(&pq).unwrap();
        assert_eq!(&bytes[..4], b"PAR1");
        let r = SerializedFileReader::new(std::fs::File::open(&pq).unwrap()).unwrap();
        assert_eq!(r.metadata().file_metadata().num_rows(), 2);
        let fields: Vec<String> = r
            .metadata()
            .file_metadata()
            .schema()
            .get_fields()
            .iter()
            .map(|f| f.name().to_string())
            .collect();
        assert_eq!(fields, COLUMNS);
        let rows: Vec<String> = r
            .get_row_iter(None)
            .unwrap()
            .map(|row| row.unwrap().to_string())
            .collect();
        assert!(
            rows[0].contains("n: 10") && rows[0].contains("peak_memory_bytes: null"),
            "{}",
            rows[0]
        );
        assert!(rows[1].contains("status: \"failed\""), "{}", rows[1]);
        // No rows: still a valid file.
        let [_, pq] = write_summary(dir.path(), &[]).unwrap();
        let r = SerializedFileReader::new(std::fs::File::open(&pq).unwrap()).unwrap();
        assert_eq!(r.metadata().file_metadata().num_rows(), 0);
    }
}
