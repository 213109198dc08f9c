//! Length-limited Huffman codes as deflate writes them: takes symbol frequencies and a
//! length limit, gives code lengths (a complete code whenever two or more symbols occur) and
//! the canonical codes of RFC 1951 §3.2.2, bit-reversed for deflate's LSB-first packing.

/// Code lengths for `freqs` (0 for unused symbols), none longer than `limit`.
///
/// A lone used symbol gets length 1. Ties are broken by symbol number, so the lengths are a
/// pure function of the frequencies. When the optimal code is too long the frequencies are
/// halved (keeping every used symbol at least 1) and the code rebuilt: the result is still a
/// Huffman code, so it stays complete.
pub fn code_lengths(freqs: &[u32], limit: u8, lengths: &mut [u8]) {
    debug_assert!(freqs.len() <= 1 << limit, "the alphabet fits the limit");
    lengths.fill(0);
    let mut leaves: Vec<(u32, u16)> = freqs
        .iter()
        .enumerate()
        .filter(|&(_, &f)| f > 0)
        .map(|(symbol, &f)| (f, symbol as u16))
        .collect();
    match leaves.len() {
        0 => return,
        1 => {
            lengths[leaves[0].1 as usize] = 1;
            return;
        }
        _ => {}
    }
    loop {
        leaves.sort_unstable();
        let depths = tree_depths(&leaves);
        if depths.iter().all(|&d| d <= limit) {
            for (&(_, symbol), &depth) in leaves.iter().zip(&depths) {
                lengths[symbol as usize] = depth;
            }
            return;
        }
        for leaf in &mut leaves {
            leaf.0 = leaf.0.div_ceil(2);
        }
    }
}

/// Depth of each leaf (sorted by weight) in a Huffman tree built with the two-queue method.
fn tree_depths(leaves: &[(u32, u16)]) -> Vec<u8> {
    let n = leaves.len();
    let mut weight: Vec<u64> = leaves.iter().map(|&(f, _)| u64::from(f)).collect();
    weight.resize(2 * n - 1, 0);
    let mut parent = vec![0usize; 2 * n - 1];
    let (mut next_leaf, mut next_node) = (0, n);
    for created in n..2 * n - 1 {
        let mut take = || {
            let leaf_first =
                next_leaf < n && (next_node == created || weight[next_leaf] <= weight[next_node]);
            let index = if leaf_first { &mut next_leaf } else { &mut next_node };
            *index += 1;
            *index - 1
        };
        let (a, b) = (take(), take());
        weight[created] = weight[a] + weight[b];
        parent[a] = created;
        parent[b] = created;
    }
    // Parents are created after their children, so one backward pass sets every depth.
    let mut depth = vec![0u8; 2 * n - 1];
    for node in (0..2 * n - 2).rev() {
        depth[node] = depth[parent[node]] + 1;
    }
    depth.truncate(n);
    depth
}

/// Canonical codes for `lengths`, each bit-reversed so it can be written LSB first.
pub fn canonical_codes(lengths: &[u8], codes: &mut [u16]) {
    let mut count = [0u16; 16];
    for &l in lengths {
        count[l as usize] += 1;
    }
    count[0] = 0;
    let mut next = [0u16; 16];
    let mut code = 0u16;
    for bits in 1..16 {
        code = (code + count[bits - 1]) << 1;
        next[bits] = code;
    }
    for (symbol, &l) in lengths.iter().enumerate() {
        if l > 0 {
            let c = next[l as usize];
            next[l as usize] += 1;
            codes[symbol] = c.reverse_bits() >> (16 - l);
        } else {
            codes[symbol] = 0;
        }
    }
}
