//! Supernode detection on explicit column patterns.

use lapclone::solve::supernodes::SupernodePartition;

/// A column pattern from explicit row lists (each starting with its diagonal).
fn pattern(columns: &[&[u32]]) -> (Vec<u32>, Vec<u32>) {
    let mut col_ptr = vec![0u32];
    let mut row_idx = Vec::new();
    for rows in columns {
        row_idx.extend_from_slice(rows);
        col_ptr.push(row_idx.len() as u32);
    }
    (col_ptr, row_idx)
}

#[test]
fn dense_lower_triangle_is_one_supernode() {
    let (cp, ri) = pattern(&[&[0, 1, 2, 3], &[1, 2, 3], &[2, 3], &[3]]);
    let p = SupernodePartition::detect(&cp, &ri);
    assert_eq!(p.begins(), &[0, 4]);
    assert_eq!(p.max_height(), 4);
    assert_eq!(p.panel_rows(0), &[0, 1, 2, 3]);
    p.sanity_check(&cp, &ri).unwrap();
}

#[test]
fn runs_split_where_the_pattern_changes() {
    // Columns 0–1 share {2, 4} below their block; column 2 gains row 3, which column 1
    // lacks, so it starts a new supernode with 3 and 4; column 4 is alone.
    let (cp, ri) = pattern(&[&[0, 1, 2, 4], &[1, 2, 4], &[2, 3, 4], &[3, 4], &[4]]);
    let p = SupernodePartition::detect(&cp, &ri);
    assert_eq!(p.begins(), &[0, 2, 5]);
    assert_eq!(p.panel_rows(0), &[0, 1, 2, 4]);
    assert_eq!(p.panel_rows(1), &[2, 3, 4]);
    assert_eq!(p.max_height(), 4);
    p.sanity_check(&cp, &ri).unwrap();
}

#[test]
fn diagonal_matrix_gives_singletons_and_empty_is_empty() {
    let (cp, ri) = pattern(&[&[0], &[1], &[2]]);
    let p = SupernodePartition::detect(&cp, &ri);
    assert_eq!(p.begins(), &[0, 1, 2, 3]);
    p.sanity_check(&cp, &ri).unwrap();
    let empty = SupernodePartition::detect(&[0], &[]);
    assert_eq!(empty.count(), 0);
    empty.sanity_check(&[0], &[]).unwrap();
}

#[test]
fn sanity_check_rejects_a_partition_of_another_pattern() {
    let (cp, ri) = pattern(&[&[0, 1, 2, 3], &[1, 2, 3], &[2, 3], &[3]]);
    let (other_cp, other_ri) = pattern(&[&[0, 2], &[1, 3], &[2, 3], &[3]]);
    let p = SupernodePartition::detect(&cp, &ri);
    assert!(p.sanity_check(&other_cp, &other_ri).is_err());
    let q = SupernodePartition::detect(&other_cp, &other_ri);
    // Maximality: the dense pattern's columns would merge into one run.
    assert!(q.sanity_check(&cp, &ri).is_err());
}
