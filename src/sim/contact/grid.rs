//! A uniform grid of cells in space, shared by the hair-hair searches:
//! the pairwise penalty's vertices (hair_pairs.rs, `EdgeGrid`) and the
//! contacts between hairs with Coulomb friction (hair_friction.rs). Cells
//! are packed into keys and counting-sorted into buckets (a spatial
//! wrap-around index), in parallel and in an order that does not depend
//! on the thread count; segments walk the cells they pass through.

use crate::sim::math::V3;

/// Cells a segment may cross in a walk; a longer one (a strand torn far
/// beyond its rest length) is searched another way by the caller.
pub(crate) const MAX_CELLS_PER_EDGE: usize = 96;

/// An item sorted into buckets by its cell.
pub(crate) trait Bucketed: Copy + Default + Send + Sync {
    /// Its cell, packed by [`pack`] (bits above the 30 of a cell are
    /// ignored).
    fn cell_key(&self) -> u32;
}

impl<E> Default for SortScratch<E> {
    fn default() -> Self {
        SortScratch {
            grouped: Vec::new(),
            part_starts: Vec::new(),
        }
    }
}

/// `floor` as an integer, saturating far away (truncation, then one down
/// for negatives: `floor` is a libm call on baseline x86-64).
#[inline]
pub(crate) fn floor_i32(x: f32) -> i32 {
    let t = x as i32;
    if (t as f32) > x {
        // Saturating: below i32::MIN the cast already gave the end cell.
        t.saturating_sub(1)
    } else {
        t
    }
}

#[inline]
pub(crate) fn cell_of(p: V3, inv_cell: f32) -> [i32; 3] {
    // Saturating float-to-int casts keep far-away points in the end cells.
    [
        floor_i32(p[0] * inv_cell),
        floor_i32(p[1] * inv_cell),
        floor_i32(p[2] * inv_cell),
    ]
}

/// A cell as one key (10 bits per axis, so an entry is 12 bytes: cells
/// alias only 1,024 cells apart, metres at the usual cell sizes, and an
/// aliased edge is then rejected by the exact distance test).
#[inline]
pub(crate) fn pack(cell: [i32; 3]) -> u32 {
    let m = (1u32 << 10) - 1;
    ((cell[0] as u32 & m) << 20) | ((cell[1] as u32 & m) << 10) | (cell[2] as u32 & m)
}

#[inline]
pub(crate) fn bucket_of(cell: [i32; 3], bits: u32) -> usize {
    let m = (1usize << bits) - 1;
    ((cell[0] as usize & m) << (2 * bits))
        | ((cell[1] as usize & m) << bits)
        | (cell[2] as usize & m)
}

/// The cell walls between cells `from` and `to`.
#[inline]
pub(crate) fn crossings(from: [i32; 3], to: [i32; 3]) -> i64 {
    (0..3)
        .map(|c| (i64::from(to[c]) - i64::from(from[c])).abs())
        .sum()
}

/// Visits the cells segment `a`-`b` passes through, walked from `a` to `b`
/// (Amanatides and Woo 1987), without repeats (hand-written: the walk is
/// a dozen lines and the hot loop of the search). Returns false, visiting
/// none, when there are `MAX_CELLS_PER_EDGE` or more. (A visitor rather
/// than an array of cells: zeroing the array was a 384-byte memset per
/// edge.)
#[inline(always)]
pub(crate) fn walk_cells(a: V3, b: V3, inv_cell: f32, mut visit: impl FnMut(u32)) -> bool {
    let Some(mut walk) = Walk::new(a, b, inv_cell) else {
        return false;
    };
    visit(pack(walk.at));
    while walk.advance().is_some() {
        visit(pack(walk.at));
    }
    true
}

/// The cell-by-cell walk of a segment (Amanatides and Woo 1987) that
/// [`walk_cells`] and [`cells_near_segment`] share.
struct Walk {
    at: [i32; 3],
    end: [i32; 3],
    step: [i32; 3],
    /// Segment parameter of the next cell wall per axis, and between walls.
    next: [f32; 3],
    delta: [f32; 3],
}

impl Walk {
    /// `None` when the segment crosses `MAX_CELLS_PER_EDGE` walls or more.
    #[inline(always)]
    fn new(a: V3, b: V3, inv_cell: f32) -> Option<Walk> {
        let at = cell_of(a, inv_cell);
        let end = cell_of(b, inv_cell);
        if crossings(at, end) >= MAX_CELLS_PER_EDGE as i64 {
            return None;
        }
        let mut step = [0i32; 3];
        let mut next = [f32::INFINITY; 3];
        let mut delta = [f32::INFINITY; 3];
        for c in 0..3 {
            let d = (b[c] - a[c]) * inv_cell;
            let x = a[c] * inv_cell;
            if end[c] > at[c] {
                step[c] = 1;
                delta[c] = 1.0 / d;
                next[c] = ((at[c] as f32 + 1.0) - x) / d;
            } else if end[c] < at[c] {
                step[c] = -1;
                delta[c] = -1.0 / d;
                next[c] = (at[c] as f32 - x) / d;
            }
        }
        Some(Walk {
            at,
            end,
            step,
            next,
            delta,
        })
    }

    /// Crosses the next wall, returning its segment parameter, or `None`
    /// in the end cell. One wall per step, on an axis not yet at the end
    /// cell, so the walk ends in `b`'s cell whatever round-off does at
    /// corners.
    #[inline(always)]
    fn advance(&mut self) -> Option<f32> {
        if self.at == self.end {
            return None;
        }
        let mut c = 3;
        for axis in 0..3 {
            if self.at[axis] != self.end[axis] && (c == 3 || self.next[axis] < self.next[c]) {
                c = axis;
            }
        }
        let t = self.next[c];
        self.at[c] += self.step[c];
        self.next[c] += self.delta[c];
        Some(t)
    }
}

/// The cells that may hold a point within `margin` of segment `a`-`b`,
/// packed by [`pack`], each once and sorted, into `cells` (emptied first):
/// the segment is cut where it crosses cell walls (as [`walk_cells`]
/// walks it), and each piece's box, grown by `margin` and a little for
/// round-off, gives its cells. Two segments closer than the sum of their
/// margins then share a cell (the point of the gap between them that is
/// within each one's margin lies in both lists). False, with `cells`
/// empty, when the segment crosses [`MAX_CELLS_PER_EDGE`] walls or more or
/// its cells are more than `max`.
pub(crate) fn cells_near_segment(
    a: V3,
    b: V3,
    margin: f32,
    inv_cell: f32,
    max: usize,
    cells: &mut Vec<u32>,
) -> bool {
    cells.clear();
    let Some(mut walk) = Walk::new(a, b, inv_cell) else {
        return false;
    };
    // f32 round-off of the pieces' ends: a few ulps of the coordinates.
    let largest = a.iter().chain(&b).fold(0.0f32, |m, c| m.max(c.abs()));
    let grow = margin * 1.001 + 8.0 * f32::EPSILON * largest;
    let point = |t: f32| -> V3 {
        let t = t.clamp(0.0, 1.0);
        std::array::from_fn(|k| a[k] + (b[k] - a[k]) * t)
    };
    // The pieces chain from 0 to 1 (each starts where the last ended), so
    // together they cover the segment whatever round-off does.
    let mut from = a;
    loop {
        let wall = walk.advance();
        let done = wall.is_none();
        let to = wall.map_or(b, point);
        let lo = cell_of(std::array::from_fn(|k| from[k].min(to[k]) - grow), inv_cell);
        let hi = cell_of(std::array::from_fn(|k| from[k].max(to[k]) + grow), inv_cell);
        let count: i64 = (0..3)
            .map(|k| i64::from(hi[k]) - i64::from(lo[k]) + 1)
            .product();
        if count < 0 || cells.len() as i64 + count > max as i64 {
            cells.clear();
            return false;
        }
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    cells.push(pack([x, y, z]));
                }
            }
        }
        if done {
            break;
        }
        from = to;
    }
    cells.sort_unstable();
    cells.dedup();
    true
}

/// Bucket ranges sorted independently (in parallel).
const PARTS: usize = 64;

/// Reusable buffers of [`sort_into_buckets`].
#[derive(Debug)]
pub(crate) struct SortScratch<E> {
    /// Per chunk, its entries grouped by part (in order within a part).
    grouped: Vec<Vec<E>>,
    /// Per chunk, where each part starts in `grouped` (and the end).
    part_starts: Vec<[u32; PARTS + 1]>,
}

/// A stable counting sort of the entries of `chunks` (in chunk order)
/// into `out` by bucket (`1 << 3 bits` of them); `starts` ends as each
/// bucket's first index and the total. Chunks first group their entries
/// by part (a range of buckets), then each part sorts its entries from
/// every chunk: both in parallel, each over data that fits in cache, and
/// the result does not depend on the thread count.
pub(crate) fn sort_into_buckets<E: Bucketed>(
    chunks: &[Vec<E>],
    bits: u32,
    scratch: &mut SortScratch<E>,
    starts: &mut Vec<u32>,
    out: &mut Vec<E>,
) {
    use rayon::prelude::*;
    let buckets = 1usize << (3 * bits);
    let per_part = buckets / PARTS;
    // Both powers of two: a shift, not a division per entry.
    let part_shift = per_part.trailing_zeros();
    let part_of = |e: &E| bucket_of(unpack(e.cell_key()), bits) >> part_shift;
    if scratch.grouped.len() < chunks.len() {
        scratch.grouped.resize_with(chunks.len(), Vec::new);
    }
    scratch.part_starts.resize(chunks.len(), [0; PARTS + 1]);
    chunks
        .par_iter()
        .zip(scratch.grouped.par_iter_mut())
        .zip(scratch.part_starts.par_iter_mut())
        .for_each(|((chunk, grouped), part_starts)| {
            *part_starts = [0; PARTS + 1];
            for e in chunk {
                part_starts[part_of(e) + 1] += 1;
            }
            for p in 1..=PARTS {
                part_starts[p] += part_starts[p - 1];
            }
            let mut cursor = *part_starts;
            // As much room as the chunk has: no allocation as it fills.
            // Every slot is written below, so only a change of length
            // touches memory here (no clearing).
            grouped.reserve(chunk.capacity().saturating_sub(grouped.len()));
            grouped.resize(chunk.len(), E::default());
            for e in chunk {
                let slot = &mut cursor[part_of(e)];
                grouped[*slot as usize] = *e;
                *slot += 1;
            }
        });
    let grouped = &scratch.grouped[..chunks.len()];
    let part_starts = &scratch.part_starts;
    let total: usize = chunks.iter().map(Vec::len).sum();
    // `out` and `starts` are written whole below: resized, not cleared
    // (clearing them was a serial pass over 20 MB at 10k strands).
    let room: usize = chunks.iter().map(Vec::capacity).sum();
    out.reserve(room.saturating_sub(out.len()));
    out.resize(total, E::default());
    starts.resize(buckets + 1, 0);
    starts[buckets] = total as u32;
    // Each part's slice of `out`, cut in order without allocating.
    let mut rest = out.as_mut_slice();
    let mut base = 0u32;
    let parts: [(u32, &mut [E]); PARTS] = std::array::from_fn(|p| {
        let size: u32 = part_starts.iter().map(|s| s[p + 1] - s[p]).sum();
        let (mine, tail) = std::mem::take(&mut rest).split_at_mut(size as usize);
        rest = tail;
        base += size;
        (base - size, mine)
    });
    parts
        .into_par_iter()
        .zip(starts[..buckets].par_chunks_mut(per_part))
        .enumerate()
        .for_each(|(p, ((base, out), starts))| {
            let first_bucket = p * per_part;
            let entries = grouped
                .iter()
                .zip(part_starts)
                .flat_map(|(g, s)| &g[s[p] as usize..s[p + 1] as usize]);
            starts.fill(0);
            for e in entries.clone() {
                starts[bucket_of(unpack(e.cell_key()), bits) - first_bucket] += 1;
            }
            let mut sum = 0;
            for s in starts.iter_mut() {
                let count = *s;
                *s = sum;
                sum += count;
            }
            for e in entries {
                let slot = &mut starts[bucket_of(unpack(e.cell_key()), bits) - first_bucket];
                out[*slot as usize] = *e;
                *slot += 1;
            }
            // The cursors hold each bucket's end: back to starts, global.
            let mut previous = 0;
            for s in starts.iter_mut() {
                let end = *s;
                *s = previous + base;
                previous = end;
            }
        });
}

#[inline]
pub(crate) fn unpack(key: u32) -> [i32; 3] {
    let m = (1u32 << 10) - 1;
    [
        ((key >> 20) & m) as i32,
        ((key >> 10) & m) as i32,
        (key & m) as i32,
    ]
}

/// Bits per axis for about one bucket per item or two: at least 2 (64
/// buckets, one per part of the sort), at most 7 (2 million buckets, 8 MB
/// of starts: more would cost more to clear than aliasing cells do).
pub(crate) fn bucket_bits(items: usize) -> u32 {
    let mut bits = 2;
    while (1usize << (3 * bits)) < items && bits < 7 {
        bits += 1;
    }
    bits
}
