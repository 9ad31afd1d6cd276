//! Greedy graph colouring: constraints of one colour share no node, so they can be projected in
//! any order, or at once, with the same result.

/// Colours `items` (each a list of node indices) greedily in the given order: each takes the
/// smallest colour none of its nodes has yet. Returns the colour of each item and the number of
/// colours.
pub(crate) fn greedy_colours<const N: usize>(
    node_count: usize,
    items: &[[u32; N]],
) -> (Vec<u32>, u32) {
    // Per node, a bitset of the colours used at it, in 64-bit words (grown as needed).
    let mut words = 1usize;
    let mut used = vec![0u64; node_count];
    let mut colours = Vec::with_capacity(items.len());
    let mut count = 0u32;
    for item in items {
        let colour = 'search: loop {
            for word in 0..words {
                let mut taken = 0u64;
                for &n in item {
                    taken |= used[n as usize * words + word];
                }
                if taken != u64::MAX {
                    break 'search word as u32 * 64 + (!taken).trailing_zeros();
                }
            }
            // Every colour so far is taken at some node: widen the bitsets by one word.
            let mut wider = vec![0u64; node_count * (words + 1)];
            for n in 0..node_count {
                wider[n * (words + 1)..n * (words + 1) + words]
                    .copy_from_slice(&used[n * words..(n + 1) * words]);
            }
            used = wider;
            words += 1;
        };
        let (word, bit) = ((colour / 64) as usize, colour % 64);
        for &n in item {
            used[n as usize * words + word] |= 1 << bit;
        }
        count = count.max(colour + 1);
        colours.push(colour);
    }
    (colours, count)
}

/// The permutation that sorts items by colour, keeping the given order within a colour, and the
/// offsets of each colour's range in it (`offsets.len() == colour_count + 1`).
pub(crate) fn colour_order(colours: &[u32], colour_count: u32) -> (Vec<usize>, Vec<u32>) {
    let mut offsets = vec![0u32; colour_count as usize + 1];
    for &c in colours {
        offsets[c as usize + 1] += 1;
    }
    for c in 0..colour_count as usize {
        offsets[c + 1] += offsets[c];
    }
    let mut next = offsets.clone();
    let mut order = vec![0usize; colours.len()];
    for (i, &c) in colours.iter().enumerate() {
        order[next[c as usize] as usize] = i;
        next[c as usize] += 1;
    }
    (order, offsets)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_colour_repeats_at_a_node_even_past_64_colours() {
        // A star: 100 edges at node 0 need 100 colours.
        let items: Vec<[u32; 2]> = (1..=100).map(|i| [0, i]).collect();
        let (colours, count) = greedy_colours(101, &items);
        assert_eq!(count, 100);
        let mut seen = colours.clone();
        seen.sort_unstable();
        seen.dedup();
        assert_eq!(seen.len(), 100);
        let (order, offsets) = colour_order(&colours, count);
        assert_eq!(offsets.len(), 101);
        assert_eq!(order.len(), 100);
        // A path colours with 2.
        let path: Vec<[u32; 2]> = (0..50).map(|i| [i, i + 1]).collect();
        assert_eq!(greedy_colours(51, &path).1, 2);
    }
}
