//! `Mesh::sanity_check` refuses each kind of broken mesh.

use glam::DVec2;
use lapclone::mesh::{assemble_mesh, LoopKind, Mesh, SanityError};

fn two_triangle_square() -> Mesh {
    let positions = vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
    assemble_mesh(positions, vec![[0, 1, 2], [0, 2, 3]])
}

#[test]
fn a_good_square_passes() {
    two_triangle_square().sanity_check().unwrap();
}

#[test]
fn flipped_triangle_fails() {
    let mut mesh = two_triangle_square();
    mesh.triangles[1] = [0, 3, 2];
    assert!(matches!(
        mesh.sanity_check(),
        Err(SanityError::NotPositive { triangle: 1, .. })
    ));
}

#[test]
fn over_shared_edge_fails() {
    let mut mesh = two_triangle_square();
    mesh.triangles.push([0, 1, 2]);
    assert!(matches!(
        mesh.sanity_check(),
        Err(SanityError::EdgeOverShared { .. })
    ));
}

#[test]
fn missing_loop_fails() {
    let mut mesh = two_triangle_square();
    mesh.loops.clear();
    assert!(mesh.sanity_check().is_err());
}

#[test]
fn wrong_flag_fails() {
    let mut mesh = two_triangle_square();
    mesh.is_boundary[2] = false;
    assert_eq!(
        mesh.sanity_check(),
        Err(SanityError::BoundaryFlag { vertex: 2 })
    );
}

#[test]
fn wrong_piece_count_fails() {
    let mut mesh = two_triangle_square();
    mesh.piece_count = 2;
    assert!(matches!(
        mesh.sanity_check(),
        Err(SanityError::PieceCount { .. })
    ));
}

#[test]
fn mislabelled_hole_fails() {
    let mut mesh = two_triangle_square();
    mesh.loops[0].kind = LoopKind::Hole;
    assert!(matches!(
        mesh.sanity_check(),
        Err(SanityError::LoopOrientation { .. })
    ));
}

#[test]
fn isolated_vertex_fails() {
    let mut mesh = two_triangle_square();
    mesh.positions.push(DVec2::new(5.0, 5.0));
    mesh.is_boundary.push(false);
    mesh.piece.push(0);
    assert_eq!(
        mesh.sanity_check(),
        Err(SanityError::IsolatedVertex { vertex: 4 })
    );
}
