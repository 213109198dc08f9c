//! Matrix Market export of a mesh's combinatorial Laplacian (vertex degree on the diagonal,
//! −1 per edge), for `lapclone mesh --laplacian-out`: takes a [`Mesh`] and gives
//! `L.mtx` ("coordinate real symmetric", lower triangle, 1-based) plus `L.mtx.boundary`
//! (0-based boundary vertex indices, one per line), both written atomically.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::{Mesh, MeshError};
use crate::util::write_atomic;

/// The Matrix Market text of the combinatorial Laplacian, entries ordered by column, then row.
pub fn laplacian_matrix_market(mesh: &Mesh) -> String {
    let n = mesh.vertex_count();
    let edges = mesh.edges();
    let mut degree = vec![0u32; n];
    // Lower-triangle entries (row > column) grouped by column = the smaller index.
    let mut below: Vec<Vec<u32>> = vec![Vec::new(); n];
    for &(i, j) in &edges {
        degree[i as usize] += 1;
        degree[j as usize] += 1;
        below[i as usize].push(j);
    }
    let mut text = String::with_capacity(32 + 24 * (n + edges.len()));
    text.push_str("%%MatrixMarket matrix coordinate real symmetric\n");
    text.push_str("% combinatorial Laplacian of a lapclone mesh\n");
    writeln!(text, "{n} {n} {}", n + edges.len()).expect("String write"); // invariant: writing into a String cannot fail.
    for (column, rows) in below.iter().enumerate() {
        writeln!(text, "{} {} {}", column + 1, column + 1, degree[column]).expect("String write"); // invariant: writing to a String cannot fail
        for &row in rows {
            let (r, c) = (row + 1, column + 1);
            writeln!(text, "{r} {c} -1").expect("String write"); // invariant: String writes cannot fail
        }
    }
    text
}

/// Boundary vertex indices (0-based), one per line.
pub fn boundary_list(mesh: &Mesh) -> String {
    mesh.boundary_vertices().map(|v| format!("{v}\n")).collect()
}

/// `path` with `.boundary` appended to its file name.
pub fn boundary_path(path: &Path) -> PathBuf {
    let mut name = path.as_os_str().to_os_string();
    name.push(".boundary");
    PathBuf::from(name)
}

/// Writes `path` and `path.boundary` atomically.
pub fn write_laplacian(mesh: &Mesh, path: &Path) -> Result<(), MeshError> {
    let write = |p: &Path, text: String| {
        write_atomic(p, text.as_bytes()).map_err(|source| MeshError::Write {
            path: p.to_path_buf(),
            source,
        })
    };
    write(path, laplacian_matrix_market(mesh))?;
    write(&boundary_path(path), boundary_list(mesh))
}

#[cfg(test)]
mod tests {
    use glam::DVec2;

    use super::super::triangulate::assemble_mesh;
    use super::*;

    #[test]
    fn square_laplacian_text() {
        let p = vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
        let mesh = assemble_mesh(p, vec![[0, 1, 2], [0, 2, 3]]);
        let text = laplacian_matrix_market(&mesh);
        let expected = "%%MatrixMarket matrix coordinate real symmetric\n\
                        % combinatorial Laplacian of a lapclone mesh\n\
                        4 4 9\n1 1 3\n2 1 -1\n3 1 -1\n4 1 -1\n2 2 2\n3 2 -1\n3 3 3\n4 3 -1\n4 4 2\n";
        assert_eq!(text, expected);
        assert_eq!(boundary_list(&mesh), "0\n1\n2\n3\n");
    }

    #[test]
    fn boundary_path_appends() {
        assert_eq!(
            boundary_path(Path::new("a/L.mtx")),
            PathBuf::from("a/L.mtx.boundary")
        );
    }
}
