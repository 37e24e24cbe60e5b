//! (c) The numeric CSV reader (torque tables, training data, logs). The first byte says
//! whether the rest is gzip-compressed (as `.csv.gz` logs are); an accepted table holds only
//! finite numbers, one per column and row, with a line for every row.

#![no_main]

use libfuzzer_sys::fuzz_target;
use neurarm::table::NumericTable;

fuzz_target!(|data: &[u8]| {
    let [how, bytes @ ..] = data else { return };
    let cursor = std::io::Cursor::new(bytes.to_vec());
    let source: Box<dyn std::io::Read> = if how & 1 != 0 { Box::new(flate2::read::MultiGzDecoder::new(cursor)) } else { Box::new(cursor) };
    let required: &[&str] = if how & 2 != 0 { &["time"] } else { &[] };
    let Ok(table) = NumericTable::from_reader(source, std::path::Path::new("fuzz.csv"), required) else { return };
    assert!(table.rows() > 0);
    assert_eq!(table.columns.len(), table.names.len());
    for column in &table.columns {
        assert_eq!(column.len(), table.rows());
        assert!(column.iter().all(|v| v.is_finite()));
    }
    if table.column("time").is_some() {
        let _ = table.require_increasing("time");
    }
});
