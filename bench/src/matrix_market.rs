//! Reads [`SymmetricCsc`] matrices in Matrix Market coordinate format (what `lapclone mesh
//! --laplacian-out` writes, or any square symmetric real matrix) and constrained-vertex lists
//! (one 0-based index per line), for `lapclone-bench solver`. Parse errors carry file and
//! line. lapclone's tests include this file for their round trip.

use lapclone::solve::{SolveError, SymmetricCsc};
use std::path::Path;

/// Reads a square `real`/`integer` coordinate matrix, `symmetric` or `general`. A `general`
/// file must be numerically symmetric (entries of the upper triangle must mirror the lower).
pub fn read_matrix_market(path: &Path) -> Result<SymmetricCsc, SolveError> {
    let text = std::fs::read_to_string(path).map_err(|source| SolveError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_matrix_market(path, &text)
}

fn parse_matrix_market(path: &Path, text: &str) -> Result<SymmetricCsc, SolveError> {
    let err = |line: usize, message: String| SolveError::Parse {
        path: path.to_path_buf(),
        line,
        message,
    };
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l));
    let (_, header) = lines.next().ok_or_else(|| err(1, "empty file".into()))?;
    let symmetric = parse_header(header).map_err(|m| err(1, m))?;
    let mut size: Option<(usize, usize)> = None;
    let mut lower = Vec::new();
    let mut upper = Vec::new();
    for (line_no, line) in lines {
        let line = line.trim();
        if line.is_empty() || line.starts_with('%') {
            continue;
        }
        let fields: Vec<&str> = line.split_whitespace().collect();
        let Some((n, _)) = size else {
            let parsed = parse_size_line(&fields).map_err(|m| err(line_no, m))?;
            lower.reserve(parsed.1);
            size = Some(parsed);
            continue;
        };
        let (i, j, v) = parse_entry(&fields, n).map_err(|m| err(line_no, m))?;
        if i >= j || symmetric {
            lower.push((i, j, v));
        } else {
            upper.push((j, i, v));
        }
    }
    let (n, nnz) =
        size.ok_or_else(|| err(text.lines().count().max(1), "missing size line".into()))?;
    if lower.len() + upper.len() != nnz {
        return Err(err(
            text.lines().count().max(1),
            format!(
                "header announces {nnz} entries, file holds {}",
                lower.len() + upper.len()
            ),
        ));
    }
    if !symmetric && !upper.is_empty() {
        check_mirrored(&mut lower, &mut upper).map_err(SolveError::InvalidMatrix)?;
    }
    SymmetricCsc::from_triplets(n, &lower)
}

/// Returns whether the file declares itself symmetric.
fn parse_header(header: &str) -> Result<bool, String> {
    let words: Vec<String> = header
        .split_whitespace()
        .map(str::to_ascii_lowercase)
        .collect();
    if words.len() != 5 || words[0] != "%%matrixmarket" || words[1] != "matrix" {
        return Err(format!("not a Matrix Market header: `{header}`"));
    }
    if words[2] != "coordinate" {
        return Err(format!(
            "only coordinate format is supported, not `{}`",
            words[2]
        ));
    }
    if words[3] != "real" && words[3] != "integer" {
        return Err(format!(
            "only real or integer fields are supported, not `{}`",
            words[3]
        ));
    }
    match words[4].as_str() {
        "symmetric" => Ok(true),
        "general" => Ok(false),
        other => Err(format!(
            "only symmetric or general matrices are supported, not `{other}`"
        )),
    }
}

fn parse_size_line(fields: &[&str]) -> Result<(usize, usize), String> {
    let numbers: Vec<usize> = fields
        .iter()
        .map(|f| {
            f.parse::<usize>()
                .map_err(|_| format!("`{f}` is not a non-negative integer"))
        })
        .collect::<Result<_, _>>()?;
    match numbers[..] {
        [rows, cols, nnz] if rows == cols => Ok((rows, nnz)),
        [rows, cols, _] => Err(format!("matrix must be square, got {rows}×{cols}")),
        _ => Err("size line must be `rows cols entries`".into()),
    }
}

fn parse_entry(fields: &[&str], n: usize) -> Result<(usize, usize, f64), String> {
    let [i, j, v] = fields else {
        return Err("entry line must be `row col value`".into());
    };
    let index = |f: &str| -> Result<usize, String> {
        match f.parse::<usize>() {
            Ok(k) if (1..=n).contains(&k) => Ok(k - 1),
            _ => Err(format!("index `{f}` is not in 1..={n}")),
        }
    };
    let value: f64 = v.parse().map_err(|_| format!("`{v}` is not a number"))?;
    if !value.is_finite() {
        return Err(format!("value `{v}` is not finite"));
    }
    Ok((index(i)?, index(j)?, value))
}

/// Checks that the transposed upper entries equal the lower ones (relative 1e-12).
fn check_mirrored(
    lower: &mut [(usize, usize, f64)],
    upper: &mut [(usize, usize, f64)],
) -> Result<(), String> {
    let strictly_lower: Vec<(usize, usize, f64)> =
        lower.iter().copied().filter(|e| e.0 != e.1).collect();
    let mut a = strictly_lower;
    a.sort_by_key(|e| (e.0, e.1));
    upper.sort_by_key(|e| (e.0, e.1));
    if a.len() != upper.len() {
        return Err("general matrix is not symmetric (pattern differs)".into());
    }
    for (x, y) in a.iter().zip(upper.iter()) {
        if (x.0, x.1) != (y.0, y.1) || (x.2 - y.2).abs() > 1e-12 * x.2.abs().max(y.2.abs()) {
            return Err(format!(
                "general matrix is not symmetric at ({}, {})",
                x.0 + 1,
                x.1 + 1
            ));
        }
    }
    Ok(())
}

/// Reads a list of 0-based vertex indices, one per line (blank lines and `#`/`%` comments
/// allowed), each checked against `n`.
pub fn read_constrained_list(path: &Path, n: usize) -> Result<Vec<usize>, SolveError> {
    let text = std::fs::read_to_string(path).map_err(|source| SolveError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let mut out = Vec::new();
    for (line_no, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') || line.starts_with('%') {
            continue;
        }
        match line.parse::<usize>() {
            Ok(v) if v < n => out.push(v),
            _ => {
                return Err(SolveError::Parse {
                    path: path.to_path_buf(),
                    line: line_no + 1,
                    message: format!("`{line}` is not a vertex index in 0..{n}"),
                })
            }
        }
    }
    Ok(out)
}
