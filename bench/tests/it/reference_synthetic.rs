//! Synthetic Table-I masks: sizes, margins, one 4-connected piece each, solvable.

use lapclone_bench::reference::synthetic::{paper_masks, spiral};
use lapclone_bench::reference::{GridMask, GridPoisson};

fn piece_count(w: usize, h: usize, inside: &[bool]) -> usize {
    let grid = GridMask::new(w, h, inside).unwrap();
    let mut seen = vec![false; w * h];
    let mut pieces = 0;
    for start in (0..w * h).filter(|&p| inside[p]) {
        if seen[start] {
            continue;
        }
        pieces += 1;
        seen[start] = true;
        let mut stack = vec![start];
        while let Some(p) = stack.pop() {
            for q in grid.neighbours(p) {
                if inside[q] && !seen[q] {
                    seen[q] = true;
                    stack.push(q);
                }
            }
        }
    }
    pieces
}

#[test]
fn masks_have_paper_sizes_margins_and_one_piece() {
    let expected = [
        ("mouth", 121, 85),
        ("raft", 342, 353),
        ("spiral", 770, 743),
        ("palm", 577, 586),
        ("snake", 470, 280),
    ];
    for (mask, (name, w, h)) in paper_masks().iter().zip(expected) {
        assert_eq!((mask.name, mask.width, mask.height), (name, w, h));
        let count = mask.inside_count();
        assert!(
            count > w * h / 10 && count < w * h * 9 / 10,
            "{name}: {count}"
        );
        let touches_border = (0..w * h)
            .filter(|&p| mask.inside[p])
            .any(|p| p % w == 0 || p % w == w - 1 || p / w == 0 || p / w == h - 1);
        assert!(!touches_border, "{name}");
        assert_eq!(piece_count(w, h, &mask.inside), 1, "{name}");
    }
}

#[test]
fn small_spiral_is_solvable_and_has_gaps() {
    let mask = spiral(160, 150);
    let grid = GridMask::new(mask.width, mask.height, &mask.inside).unwrap();
    assert!(GridPoisson::new(grid).is_ok());
    // The arms are separated: a horizontal line from the centre crosses outside pixels.
    let row = mask.height / 2;
    let crossings = (mask.width / 2..mask.width - 1)
        .filter(|&x| mask.inside[row * mask.width + x] != mask.inside[row * mask.width + x + 1])
        .count();
    assert!(crossings >= 4, "{crossings}");
}
