//! A small CSV front end shared by the readers: records with their line numbers, and numeric cells with
//! errors that name the file, line and column.

use std::path::Path;

use crate::IoError;

/// One record: its 1-based line and its cells, trimmed.
pub(crate) struct Record {
    pub line: usize,
    pub cells: Vec<String>,
}

/// Splits CSV text (LF or CRLF, any mix) into records, skipping blank lines. A file whose first line
/// holds semicolons or tabs but no comma is refused as using the wrong delimiter.
pub(crate) fn records(path: &Path, text: &str) -> Result<Vec<Record>, IoError> {
    if let Some(first) = text.lines().find(|l| !l.trim().is_empty()) {
        check_delimiter(path, first)?;
    }
    // Line by line: none of these formats has a quoted field spanning lines, and this keeps the line
    // numbers exact whatever the mix of CRLF and LF.
    let mut out = Vec::new();
    for (index, raw) in text.split('\n').enumerate() {
        if let Some(r) = record(path, index + 1, raw)? {
            out.push(r);
        }
    }
    Ok(out)
}

/// Records of a tracker export in any of the three dialects they come in, told apart by the first line
/// that is not a comment: commas (decimal points); semicolons (decimal commas, as spreadsheets in most of
/// Europe write them: `1,5` is read 1.5); or whitespace (tabs or runs of spaces, decimal points).
pub(crate) fn records_any_dialect(path: &Path, text: &str) -> Result<Vec<Record>, IoError> {
    let first = text.lines().map(str::trim).find(|l| !l.is_empty() && !l.starts_with('#')).unwrap_or("");
    if first.contains(',') && !first.contains(';') {
        return records(path, text);
    }
    let semicolons = first.contains(';');
    let mut out = Vec::new();
    for (index, raw) in text.split('\n').enumerate() {
        let raw = raw.strip_suffix('\r').unwrap_or(raw);
        let trimmed = raw.trim();
        if trimmed.is_empty() || trimmed.starts_with('#') {
            continue;
        }
        let cells: Vec<String> = if semicolons {
            trimmed.split(';').map(|c| c.trim().replace(',', ".")).collect()
        } else {
            trimmed.split_whitespace().map(str::to_string).collect()
        };
        out.push(Record { line: index + 1, cells });
    }
    Ok(out)
}

/// Refuses a first line that holds semicolons or tabs but no comma (the wrong delimiter).
pub(crate) fn check_delimiter(path: &Path, first: &str) -> Result<(), IoError> {
    if !first.contains(',') && (first.contains(';') || first.contains('\t')) {
        return Err(IoError::input(path, Some(1), "delimiter", "expected commas; this file uses ';' or tabs"));
    }
    Ok(())
}

/// One line (without or with its `\r`) as a record; `None` for blank lines and `#` comment lines (the
/// fixtures carry their provenance so).
pub(crate) fn record(path: &Path, line: usize, raw: &str) -> Result<Option<Record>, IoError> {
    let raw = raw.strip_suffix('\r').unwrap_or(raw);
    if raw.trim().is_empty() || raw.trim_start().starts_with('#') {
        return Ok(None);
    }
    // Fast path: a line without quotes is its comma-separated cells (what the csv crate would give).
    if !raw.contains('"') {
        let cells: Vec<String> = raw.split(',').map(|c| c.trim().to_string()).collect();
        return Ok((!cells.iter().all(|c| c.is_empty())).then_some(Record { line, cells }));
    }
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .buffer_capacity(raw.len() + 16)
        .from_reader(raw.as_bytes());
    let mut rec = csv::StringRecord::new();
    if let Err(e) = reader.read_record(&mut rec) {
        return Err(IoError::input(path, Some(line), "csv", e.to_string()));
    }
    let cells: Vec<String> = rec.iter().map(|c| c.trim().to_string()).collect();
    if cells.iter().all(|c| c.is_empty()) {
        return Ok(None);
    }
    Ok(Some(Record { line, cells }))
}

/// Parses a finite number from a cell; the error names the column.
pub(crate) fn number(path: &Path, line: usize, column: &str, cell: &str) -> Result<f64, IoError> {
    let v: f64 =
        cell.parse().map_err(|_| IoError::input(path, Some(line), column, format!("`{cell}` is not a number")))?;
    if !v.is_finite() {
        return Err(IoError::input(path, Some(line), column, format!("`{cell}` is not a finite number")));
    }
    Ok(v)
}

/// Finds a column by name (case-insensitive) in a header record.
pub(crate) fn column(header: &Record, name: &str) -> Option<usize> {
    header.cells.iter().position(|c| c.eq_ignore_ascii_case(name))
}

/// Checks that a record has `expected` fields; the error names the line.
pub(crate) fn expect_fields(path: &Path, r: &Record, expected: usize) -> Result<(), IoError> {
    if r.cells.len() == expected {
        Ok(())
    } else {
        Err(IoError::input(path, Some(r.line), "row", format!("{} fields, expected {expected}", r.cells.len())))
    }
}
