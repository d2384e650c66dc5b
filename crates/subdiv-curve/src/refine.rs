//! The refinement engine shared by every scheme: depth-first refinement in cache-sized
//! blocks, with inner loops specialised on the rule lengths.
//!
//! **Fused levels.** Refining level by level writes every intermediate polygon to memory
//! and reads it back: about twice the final output written and once more read, for a
//! million-point result far more than the caches hold. Instead, the output is cut into
//! blocks of `BLOCK_BYTES`; for each block the engine works out, level by level
//! downwards, which points of each coarser level it depends on (the block's stencil
//! support, a few points more per level), gathers them from the input, refines them
//! through all levels in two small scratch buffers that stay in L1/L2, and writes the
//! finest level once, straight into its place in the output. Neighbouring blocks
//! recompute the few shared support points instead of exchanging them.
//!
//! **Same numbers.** Every point of every level is computed by the same expression from
//! the same inputs as level by level (rules sum their terms in one fixed order, see
//! `Rule::apply`; phantom points are rebuilt per level from the same real points by the
//! same formula; a closed polygon's wrapped copies are computed from wrapped copies), so
//! the fused result equals the level-by-level one bit for bit; a property test checks it
//! on random polygons, open and closed, for every shipped and for random user-defined
//! schemes and the framework.
//!
//! **Threads.** Blocks are independent, so an output of at least 65,536 points per worker
//! is split into one contiguous run of whole blocks per thread of the current rayon
//! pool, each worker with its own scratch (kept in the [`Refiner`]); every point is still
//! computed by the same expression, so the result is the same bit for bit on any number
//! of threads (tested on 1, 2 and 3). Run the call inside a one-thread pool
//! (`rayon::ThreadPoolBuilder::new().num_threads(1)`) to keep it on the calling thread.
//!
//! **Level by level** (`step`, `fill_halo`) remains as the reference: one level reads
//! the current polygon from a buffer that carries a few extra points on each side (the
//! *halo*: wrapped points of a closed polygon, phantom points of an open one, see
//! [`EndRule`]), so that the inner loop needs no index arithmetic and no branches.

use crate::scheme::{CurveScheme, EndRule, Layout, Rule, Topology};
use crate::{CurveError, CurvePoint};

/// Reusable refinement context: keeps its work buffers (the cache-sized scratch of the
/// fused levels) between calls, so refining many polygons (or the same one many times,
/// as in a benchmark) allocates nothing after the first call.
///
/// ```
/// use subdiv_curve::{CurveScheme, Refiner, Topology};
/// let mut refiner = Refiner::new();
/// let mut out = Vec::new();
/// let triangle = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
/// refiner.refine_into(&CurveScheme::cubic_bspline(), &triangle, Topology::Closed, 4, &mut out)?;
/// assert_eq!(out.len(), 3 << 4);
/// # Ok::<(), subdiv_curve::CurveError>(())
/// ```
#[derive(Debug, Clone)]
pub struct Refiner<P> {
    pub(crate) front: Vec<P>,
    pub(crate) back: Vec<P>,
    /// Polygon length per level of the current call.
    pub(crate) lens: Vec<usize>,
    /// Range of extended indices each level of the current block keeps in scratch.
    pub(crate) windows: Vec<Window>,
    /// Scratch of the other workers when blocks are refined on several threads.
    pub(crate) spare: Vec<Scratch<P>>,
}

/// One worker's scratch levels and windows (see [`Refiner`]).
#[derive(Debug, Clone)]
pub(crate) struct Scratch<P> {
    front: Vec<P>,
    back: Vec<P>,
    windows: Vec<Window>,
}

impl<P> Default for Scratch<P> {
    fn default() -> Self {
        Scratch { front: Vec::new(), back: Vec::new(), windows: Vec::new() }
    }
}

/// Fewest output points per worker before blocks are spread over threads: below this the
/// hand-off costs more than it saves.
const PARALLEL_MIN_POINTS: usize = 1 << 16;

/// Target size of one output block of the fused path. The scratch levels of a block
/// (half the block, a quarter, ...) then take at most 256 KiB together and stay in L2
/// while the block streams out. Measured on 10 levels of 1,000 points (CPU time per
/// refinement, 2D cubic B-spline): 32 KiB blocks 1.36 ms, 128 KiB 1.27 ms, 256 KiB to
/// 2 MiB 1.23-1.29 ms: smaller blocks lose to the per-level overhead of tiny windows.
pub(crate) const BLOCK_BYTES: usize = 256 * 1024;

/// Output points per block for points of type `P`.
pub(crate) fn block_len<P>() -> usize {
    (BLOCK_BYTES / size_of::<P>().max(1)).max(64)
}

/// A range `first..end` of extended indices of one level: negative or `>= n` indices are
/// wrapped copies (closed polygon) or phantom points (open polygon).
pub(crate) type Window = (i64, i64);

impl<P: CurvePoint> Default for Refiner<P> {
    fn default() -> Self {
        Self::new()
    }
}

/// Halo sizes (points before, points after) for a polygon of `n` points.
pub(crate) fn halo(scheme: &CurveScheme, n: usize, topology: Topology) -> (usize, usize) {
    match topology {
        Topology::Open(_) => scheme.open_halo(n),
        Topology::Closed => {
            let (even_lo, even_hi) = scheme.even_rule().reach();
            let (odd_lo, odd_hi) = scheme.odd_rule().reach();
            ((-even_lo.min(odd_lo)).max(0) as usize, even_hi.max(odd_hi).max(0) as usize)
        }
    }
}

/// Fills the halo of `buffer` = `[left halo | n points | right halo]`.
pub(crate) fn fill_halo<P: CurvePoint>(buffer: &mut [P], left: usize, n: usize, right: usize, topology: Topology) {
    debug_assert!(buffer.len() >= left + n + right && n > 0);
    for k in 1..=left {
        buffer[left - k] = match topology {
            Topology::Closed => buffer[left + (n - k % n) % n],
            Topology::Open(EndRule::Reflect) => buffer[left].scale(2.0).minus(buffer[left + k.min(n - 1)]),
            Topology::Open(EndRule::Repeat) => buffer[left],
        };
    }
    let last = left + n - 1;
    for k in 1..=right {
        buffer[last + k] = match topology {
            Topology::Closed => buffer[left + (n - 1 + k) % n],
            Topology::Open(EndRule::Reflect) => buffer[last].scale(2.0).minus(buffer[last - k.min(n - 1)]),
            Topology::Open(EndRule::Repeat) => buffer[last],
        };
    }
}

/// One level: `source` holds the `n` current points at `left..left + n` with a filled
/// halo; `target` receives exactly `scheme.next_len(n)` points.
#[cfg(test)]
pub(crate) fn step<P: CurvePoint>(
    scheme: &CurveScheme,
    source: &[P],
    left: usize,
    n: usize,
    topology: Topology,
    target: &mut [P],
) {
    debug_assert_eq!(target.len(), scheme.next_len(n, topology));
    let (even, odd) = (scheme.even_rule(), scheme.odd_rule());
    // Index in `source` of the first point read by a rule applied at coarse index `i`.
    let base = |rule: &Rule, i: usize| (left as i64 + i as i64 + rule.offset() as i64) as usize;
    match (topology, scheme.layout()) {
        (Topology::Closed, _) => pairs(even, odd, source, base(even, 0), base(odd, 0), target),
        (Topology::Open(_), Layout::Primal) => {
            let (pairs_part, last) = target.split_at_mut(2 * (n - 1));
            pairs(even, odd, source, base(even, 0), base(odd, 0), pairs_part);
            last[0] = even.apply((left + n - 1) as i64, |j| source[j as usize]);
            if topology == Topology::Open(EndRule::Reflect) && scheme.reflect_keeps_ends() {
                (pairs_part[0], last[0]) = (source[left], source[left + n - 1]);
            }
        }
        (Topology::Open(_), Layout::Dual) => {
            let end = target.len() - 1;
            target[0] = source[left];
            target[end] = source[left + n - 1];
            pairs(even, odd, source, base(even, 0), base(odd, 0), &mut target[1..end]);
        }
    }
}

/// `target[2i] = even rule at source[even_base + i ..]`, `target[2i+1] = odd rule at
/// source[odd_base + i ..]`, dispatched to a loop specialised on the two rule lengths.
fn pairs<P: CurvePoint>(even: &Rule, odd: &Rule, source: &[P], even_base: usize, odd_base: usize, target: &mut [P]) {
    macro_rules! dispatch {
        ($(($e:literal, $o:literal)),*) => {
            match (even.weights().len(), odd.weights().len()) {
                $(($e, $o) => pairs_fixed::<P, $e, $o>(even.weights(), odd.weights(), source, even_base, odd_base, target),)*
                _ => pairs_any(even.weights(), odd.weights(), source, even_base, odd_base, target),
            }
        };
    }
    dispatch!(
        (1, 1),
        (1, 2),
        (1, 3),
        (1, 4),
        (1, 5),
        (1, 6),
        (2, 1),
        (2, 2),
        (2, 3),
        (2, 4),
        (2, 5),
        (2, 6),
        (3, 1),
        (3, 2),
        (3, 3),
        (3, 4),
        (3, 5),
        (3, 6),
        (4, 1),
        (4, 2),
        (4, 3),
        (4, 4),
        (4, 5),
        (4, 6),
        (5, 1),
        (5, 2),
        (5, 3),
        (5, 4),
        (5, 5),
        (5, 6)
    )
}

#[inline(always)]
fn weighted<P: CurvePoint, const N: usize>(weights: &[f64; N], points: &[P]) -> P {
    let points: &[P; N] = points.try_into().expect("internal: window length");
    let mut sum = points[0].scale(weights[0]);
    for k in 1..N {
        sum = sum.plus(points[k].scale(weights[k]));
    }
    sum
}

fn pairs_fixed<P: CurvePoint, const E: usize, const O: usize>(
    even: &[f64],
    odd: &[f64],
    source: &[P],
    even_base: usize,
    odd_base: usize,
    target: &mut [P],
) {
    let even: &[f64; E] = even.try_into().expect("internal: even rule length");
    let odd: &[f64; O] = odd.try_into().expect("internal: odd rule length");
    let count = target.len() / 2;
    if count == 0 {
        return;
    }
    let even_source = &source[even_base..even_base + count + E - 1];
    let odd_source = &source[odd_base..odd_base + count + O - 1];
    for ((pair, even_window), odd_window) in
        target.chunks_exact_mut(2).zip(even_source.windows(E)).zip(odd_source.windows(O))
    {
        pair[0] = weighted(even, even_window);
        pair[1] = weighted(odd, odd_window);
    }
}

fn pairs_any<P: CurvePoint>(
    even: &[f64],
    odd: &[f64],
    source: &[P],
    even_base: usize,
    odd_base: usize,
    target: &mut [P],
) {
    // Same order of operations as `weighted` and `Rule::apply`: first term, then the rest.
    let sum = |weights: &[f64], window: &[P]| {
        weights.iter().zip(window).skip(1).fold(window[0].scale(weights[0]), |acc, (&w, &p)| acc.plus(p.scale(w)))
    };
    for (i, pair) in target.chunks_exact_mut(2).enumerate() {
        pair[0] = sum(even, &source[even_base + i..]);
        pair[1] = sum(odd, &source[odd_base + i..]);
    }
}

impl<P: CurvePoint> Refiner<P> {
    /// An empty context (buffers grow on first use).
    pub fn new() -> Self {
        Refiner { front: Vec::new(), back: Vec::new(), lens: Vec::new(), windows: Vec::new(), spare: Vec::new() }
    }

    /// Refines `points` `levels` times with `scheme`, writing the result into `out`
    /// (replaced entirely; its allocation is reused).
    ///
    /// # Errors
    /// [`CurveError::TooFewPoints`] (see [`CurveScheme::min_points`]),
    /// [`CurveError::NonFinite`] for a NaN or infinite coordinate, [`CurveError::Overflow`]
    /// when finite coordinates near `f64::MAX` refine to points that are not finite,
    /// [`CurveError::TooLarge`] when the result would have more than
    /// [`MAX_REFINED_POINTS`](crate::MAX_REFINED_POINTS) points.
    ///
    /// # Performance
    /// Linear in the output size; no allocation once the buffers have reached their size.
    ///
    /// ```
    /// use subdiv_curve::{CurveScheme, Refiner, Topology};
    /// let mut out = Vec::new();
    /// let result = Refiner::new().refine_into(&CurveScheme::chaikin(), &[[0.0, f64::NAN]; 3], Topology::Closed, 1, &mut out);
    /// assert!(result.is_err());
    /// ```
    pub fn refine_into(
        &mut self,
        scheme: &CurveScheme,
        points: &[P],
        topology: Topology,
        levels: u32,
        out: &mut Vec<P>,
    ) -> Result<(), CurveError> {
        scheme.validate(points, topology)?;
        scheme.checked_refined_len(points.len(), topology, levels)?;
        self.refine_fused(scheme, points, topology, levels, out, block_len::<P>());
        if !scheme.cannot_overflow(points, levels) {
            crate::point::check_result_finite("refinement", out)?;
        }
        Ok(())
    }

    /// The fused path with `block` output points per block (see the module docs).
    pub(crate) fn refine_fused(
        &mut self,
        scheme: &CurveScheme,
        points: &[P],
        topology: Topology,
        levels: u32,
        out: &mut Vec<P>,
        block: usize,
    ) {
        debug_assert!(block > 0 && points.len() >= scheme.min_points(topology));
        if self.size_output(scheme, points, topology, levels, out) {
            self.refine_blocks(scheme, topology, points, out, block, 0, || (), |_, _| {});
        }
    }

    /// Records the polygon length of every level in `self.lens` and gives `out` the
    /// finest one. Returns `false` when there is nothing left to refine (`levels == 0`:
    /// `out` is then a copy of `points`).
    pub(crate) fn size_output(
        &mut self,
        scheme: &CurveScheme,
        points: &[P],
        topology: Topology,
        levels: u32,
        out: &mut Vec<P>,
    ) -> bool {
        self.lens.clear();
        self.lens.push(points.len());
        for _ in 0..levels {
            let n = *self.lens.last().expect("internal: level 0 is present");
            self.lens.push(scheme.next_len(n, topology));
        }
        let total = *self.lens.last().expect("internal: level 0 is present");
        // Every entry is overwritten by the caller: keep the old ones instead of zeroing
        // (a reused output of the same length costs no extra pass).
        out.truncate(total);
        out.resize(total, P::zero());
        if levels == 0 {
            out.copy_from_slice(points);
        }
        levels > 0
    }

    /// Refines the finest level into `out` (already of its length, `self.lens` set) block
    /// by block, each block widened by `margin` (see [`refine_block`]); `hook` runs after
    /// every level of every block with its worker's own `state` (made by `make_state`).
    ///
    /// Blocks are independent: with several threads each worker refines one contiguous
    /// run of whole blocks with its own scratch. Every output point is computed by the
    /// same arithmetic whichever worker owns it, so the result is bit-identical for any
    /// thread count (as long as `hook` only depends on its block, as it must anyway).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn refine_blocks<S>(
        &mut self,
        scheme: &CurveScheme,
        topology: Topology,
        points: &[P],
        out: &mut [P],
        block: usize,
        margin: i64,
        make_state: impl Fn() -> S + Sync,
        hook: impl Fn(&mut S, BlockLevel<'_, P>) + Sync,
    ) {
        let total = out.len();
        let blocks = total.div_ceil(block);
        let workers = rayon::current_num_threads().min(blocks).min(total / PARALLEL_MIN_POINTS).max(1);
        self.spare.resize_with(workers - 1, Scratch::default);
        let run = blocks.div_ceil(workers) * block;
        let lens = &self.lens;
        let mut scratch: Vec<(&mut Vec<P>, &mut Vec<P>, &mut Vec<Window>)> =
            std::iter::once((&mut self.front, &mut self.back, &mut self.windows))
                .chain(self.spare.iter_mut().map(|s| (&mut s.front, &mut s.back, &mut s.windows)))
                .collect();
        let refine_run =
            |run_index: usize,
             run_target: &mut [P],
             (front, back, windows): &mut (&mut Vec<P>, &mut Vec<P>, &mut Vec<Window>)| {
                let mut state = make_state();
                for (index, target) in run_target.chunks_mut(block).enumerate() {
                    let first = (run_index * run + index * block) as i64;
                    let range = (first, first + target.len() as i64);
                    let buffers = [&mut **front, &mut **back];
                    refine_block(
                        scheme,
                        topology,
                        points,
                        lens,
                        windows,
                        range,
                        buffers,
                        target,
                        margin,
                        &mut |level| hook(&mut state, level),
                    );
                }
            };
        if workers == 1 {
            refine_run(0, out, &mut scratch[0]);
        } else {
            use rayon::prelude::*;
            out.par_chunks_mut(run)
                .zip(scratch.par_iter_mut())
                .enumerate()
                .for_each(|(run_index, (run_target, worker))| refine_run(run_index, run_target, worker));
        }
    }

    /// The level-by-level reference path (see the module docs).
    #[cfg(test)]
    pub(crate) fn refine_levelwise(
        &mut self,
        scheme: &CurveScheme,
        points: &[P],
        topology: Topology,
        levels: u32,
        out: &mut Vec<P>,
    ) {
        if levels == 0 {
            out.clear();
            out.extend_from_slice(points);
            return;
        }
        let (left, right) = halo(scheme, points.len(), topology);
        let penultimate = scheme.refined_len(points.len(), topology, levels - 1);
        let capacity = penultimate + left + right;
        for buffer in [&mut self.front, &mut self.back] {
            if buffer.len() < capacity {
                buffer.resize(capacity, P::zero());
            }
        }
        let mut n = points.len();
        self.front[left..left + n].copy_from_slice(points);
        for level in 0..levels {
            fill_halo(&mut self.front, left, n, right, topology);
            let next = scheme.next_len(n, topology);
            if level + 1 == levels {
                out.truncate(next);
                out.resize(next, P::zero());
                step(scheme, &self.front, left, n, topology, out);
            } else {
                step(scheme, &self.front, left, n, topology, &mut self.back[left..left + next]);
                std::mem::swap(&mut self.front, &mut self.back);
            }
            n = next;
        }
    }
}

/// Extended indices of level `k` read by the rules that make the fine points `fine` of
/// level `k + 1` (`coarse_len` and `fine_len` are the two polygon lengths).
fn reads_of(scheme: &CurveScheme, topology: Topology, coarse_len: usize, fine_len: usize, fine: Window) -> Window {
    let (mut lo, mut hi) = (i64::MAX, i64::MIN);
    let (mut u0, mut u1) = fine;
    if let (Topology::Open(_), Layout::Dual) = (topology, scheme.layout()) {
        // The end points are copies; the rules make fine points 1..fine_len - 1 as rule
        // indices 0..fine_len - 2.
        if u0 == 0 {
            (lo, hi) = (0, 1);
        }
        if u1 == fine_len as i64 {
            (lo, hi) = (lo.min(coarse_len as i64 - 1), coarse_len as i64);
        }
        (u0, u1) = (u0.max(1) - 1, u1.min(fine_len as i64 - 1) - 1);
    }
    let rule = |u: i64| if u.rem_euclid(2) == 0 { scheme.even_rule() } else { scheme.odd_rule() };
    // First reads grow with the rule index within each parity: look at the first and the
    // last point of each parity.
    for u in [u0, u0 + 1] {
        if u < u1 {
            lo = lo.min(u.div_euclid(2) + rule(u).offset() as i64);
        }
    }
    for u in [u1 - 1, u1 - 2] {
        if u >= u0 {
            let r = rule(u);
            hi = hi.max(u.div_euclid(2) + r.offset() as i64 + r.weights().len() as i64);
        }
    }
    debug_assert!(lo < hi);
    (lo, hi)
}

/// One level of a block, as handed to the `after_level` hook of [`refine_block`] once the
/// rules have made the real points of the finer level (and before its phantom points are
/// filled).
pub(crate) struct BlockLevel<'a, P> {
    /// The coarser level's number (0 = input).
    pub(crate) level: usize,
    /// Its window: points at extended indices `source_first..`.
    pub(crate) source: &'a [P],
    pub(crate) source_first: i64,
    /// Its polygon length.
    pub(crate) coarse_len: usize,
    /// The finer level's real points (extended ones for a closed polygon) at indices
    /// `target_first..`.
    pub(crate) target: &'a mut [P],
    pub(crate) target_first: i64,
    /// The finer level's polygon length.
    pub(crate) fine_len: usize,
}

/// Refines the output points `range` (of the finest level) into `target`. Every window
/// is widened by `margin` points on each side (and an open polygon's real points by
/// `margin` more past the phantom points' sources) for hooks that read further than
/// the rules; `after_level` may then overwrite target points from the source window.
#[allow(clippy::too_many_arguments)]
pub(crate) fn refine_block<P: CurvePoint>(
    scheme: &CurveScheme,
    topology: Topology,
    points: &[P],
    lens: &[usize],
    windows: &mut Vec<Window>,
    range: Window,
    [mut front, mut back]: [&mut Vec<P>; 2],
    target: &mut [P],
    margin: i64,
    after_level: &mut impl FnMut(BlockLevel<'_, P>),
) {
    let levels = lens.len() - 1;
    // Downwards: the window each coarser level must provide.
    windows.clear();
    windows.resize(levels, (0, 0));
    let mut computed = range;
    for k in (0..levels).rev() {
        let reads = reads_of(scheme, topology, lens[k], lens[k + 1], computed);
        let reads = (reads.0 - margin, reads.1 + margin);
        windows[k] = match topology {
            Topology::Closed => {
                computed = reads;
                reads
            }
            Topology::Open(_) => {
                // Real points to compute: those read, plus those the phantom points read.
                let n = lens[k] as i64;
                let (mut lo, mut hi) = (reads.0.max(0), reads.1.min(n));
                if reads.0 < 0 {
                    (lo, hi) = (0, hi.max((margin - reads.0).min(n - 1) + 1));
                }
                if reads.1 > n {
                    (lo, hi) = (lo.min(n - 1 - (margin + reads.1 - n).min(n - 1)), n);
                }
                computed = (lo, hi);
                (reads.0.min(lo), reads.1.max(hi))
            }
        };
    }
    // Upwards: gather level 0, then refine level by level within the block.
    let (first, end) = windows[0];
    let n = lens[0];
    grow(front, (end - first) as usize);
    match topology {
        Topology::Closed => {
            for (slot, j) in front.iter_mut().zip(first..end) {
                *slot = points[j.rem_euclid(n as i64) as usize];
            }
        }
        Topology::Open(rule) => {
            let (lo, hi) = (first.max(0), end.min(n as i64));
            front[(lo - first) as usize..(hi - first) as usize].copy_from_slice(&points[lo as usize..hi as usize]);
            fill_phantoms(&mut front[..(end - first) as usize], first, n, rule);
        }
    }
    for k in 1..=levels {
        let source_window = windows[k - 1];
        let source = &front[..(source_window.1 - source_window.0) as usize];
        let (coarse_len, fine_len) = (lens[k - 1], lens[k]);
        let mut made = |target: &mut [P], target_first: i64| {
            fine_points(scheme, topology, coarse_len, fine_len, source, source_window.0, target_first, target);
            let level = k - 1;
            after_level(BlockLevel {
                level,
                source,
                source_first: source_window.0,
                coarse_len,
                target,
                target_first,
                fine_len,
            });
        };
        if k == levels {
            made(target, range.0);
            break;
        }
        let (first, end) = windows[k];
        let len = (end - first) as usize;
        grow(back, len);
        match topology {
            Topology::Closed => made(&mut back[..len], first),
            Topology::Open(rule) => {
                let (lo, hi) = (first.max(0), end.min(fine_len as i64));
                made(&mut back[(lo - first) as usize..(hi - first) as usize], lo);
                fill_phantoms(&mut back[..len], first, fine_len, rule);
            }
        }
        std::mem::swap(&mut front, &mut back);
    }
}

fn grow<P: CurvePoint>(buffer: &mut Vec<P>, len: usize) {
    if buffer.len() < len {
        buffer.resize(len, P::zero());
    }
}

/// Fills the phantom points of `window` (extended indices `first..`, real points of an
/// open polygon of `n` points already in place) by the formula of `fill_halo`.
fn fill_phantoms<P: CurvePoint>(window: &mut [P], first: i64, n: usize, rule: EndRule) {
    let n = n as i64;
    let at = |j: i64| (j - first) as usize;
    let end = first + window.len() as i64;
    for j in first..end.min(0) {
        let k = -j;
        window[at(j)] = match rule {
            EndRule::Reflect => window[at(0)].scale(2.0).minus(window[at(k.min(n - 1))]),
            EndRule::Repeat => window[at(0)],
        };
    }
    for j in first.max(n)..end {
        let k = j - (n - 1);
        window[at(j)] = match rule {
            EndRule::Reflect => window[at(n - 1)].scale(2.0).minus(window[at(n - 1 - k.min(n - 1))]),
            EndRule::Repeat => window[at(n - 1)],
        };
    }
}

/// Fine points `fine_first..fine_first + target.len()` (real indices of an open polygon,
/// extended ones of a closed polygon) from `source`, which holds the coarse extended
/// indices `source_first..`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn fine_points<P: CurvePoint>(
    scheme: &CurveScheme,
    topology: Topology,
    coarse_len: usize,
    fine_len: usize,
    source: &[P],
    source_first: i64,
    fine_first: i64,
    target: &mut [P],
) {
    let (even, odd) = (scheme.even_rule(), scheme.odd_rule());
    match (topology, scheme.layout()) {
        (Topology::Open(_), Layout::Dual) => {
            let (mut lo, mut hi) = (0, target.len());
            if fine_first == 0 && hi > 0 {
                target[0] = source[(0 - source_first) as usize];
                lo = 1;
            }
            if fine_first + target.len() as i64 == fine_len as i64 && hi > lo {
                target[hi - 1] = source[(coarse_len as i64 - 1 - source_first) as usize];
                hi -= 1;
            }
            by_rules(even, odd, source, source_first, fine_first + lo as i64 - 1, &mut target[lo..hi]);
        }
        (Topology::Open(EndRule::Reflect), Layout::Primal) if scheme.reflect_keeps_ends() => {
            by_rules(even, odd, source, source_first, fine_first, target);
            // The end points are kept exactly (see `CurveScheme::reflect_keeps_ends`).
            let fine_end = fine_first + target.len() as i64;
            if fine_first == 0 && !target.is_empty() {
                target[0] = source[(0 - source_first) as usize];
            }
            if fine_end == fine_len as i64 && !target.is_empty() {
                target[target.len() - 1] = source[(coarse_len as i64 - 1 - source_first) as usize];
            }
        }
        _ => by_rules(even, odd, source, source_first, fine_first, target),
    }
}

/// `target[m]` = rule point `u0 + m`: even rule at `u / 2` for even `u`, odd rule at
/// `(u - 1) / 2` for odd `u`.
fn by_rules<P: CurvePoint>(even: &Rule, odd: &Rule, source: &[P], source_first: i64, u0: i64, target: &mut [P]) {
    let at = |j: i64| source[(j - source_first) as usize];
    let mut u = u0;
    let mut start = 0;
    if u.rem_euclid(2) == 1 && !target.is_empty() {
        target[0] = odd.apply(u.div_euclid(2), at);
        start = 1;
        u += 1;
    }
    let target = &mut target[start..];
    let i = u.div_euclid(2);
    let pair_len = target.len() / 2 * 2;
    let (pair_part, rest) = target.split_at_mut(pair_len);
    let base = |rule: &Rule| (i + rule.offset() as i64 - source_first) as usize;
    pairs(even, odd, source, base(even), base(odd), pair_part);
    if let Some(last) = rest.first_mut() {
        *last = even.apply(i + (pair_len / 2) as i64, at);
    }
}

impl CurveScheme {
    /// Refines `points` `levels` times (a fresh [`Refiner`]; use one directly to reuse
    /// buffers).
    ///
    /// # Errors
    /// [`CurveError::TooFewPoints`] (see [`CurveScheme::min_points`]),
    /// [`CurveError::NonFinite`] for a NaN or infinite coordinate, [`CurveError::Overflow`]
    /// when finite coordinates near `f64::MAX` refine to points that are not finite.
    ///
    /// ```
    /// use glam::DVec3;
    /// use subdiv_curve::{CurveScheme, EndRule, Topology};
    /// let open = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 1.0)];
    /// let fine = CurveScheme::cubic_bspline().refine(&open, Topology::Open(EndRule::Reflect), 3)?;
    /// assert_eq!((fine.len(), fine[0], fine[16]), (17, open[0], open[2])); // reflect keeps the ends
    /// let err = CurveScheme::cubic_bspline().refine(&open[..1], Topology::open(), 3).unwrap_err();
    /// assert!(err.to_string().contains("at least 2 points"));
    /// # Ok::<(), subdiv_curve::CurveError>(())
    /// ```
    pub fn refine<P: CurvePoint>(&self, points: &[P], topology: Topology, levels: u32) -> Result<Vec<P>, CurveError> {
        let mut out = Vec::new();
        Refiner::new().refine_into(self, points, topology, levels, &mut out)?;
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;
    use proptest::prelude::*;

    use super::*;

    /// An affine rule from free weights: the last weight takes up the difference to 1.
    fn arb_rule() -> impl Strategy<Value = Rule> {
        (-3i32..=1, prop::collection::vec(-0.9f64..0.9, 1..=7)).prop_filter_map("degenerate rule", |(offset, mut w)| {
            let sum: f64 = w.iter().sum();
            *w.last_mut().expect("non-empty") += 1.0 - sum;
            Rule::new(offset, &w).ok()
        })
    }

    fn arb_scheme() -> impl Strategy<Value = CurveScheme> {
        prop_oneof![
            Just(CurveScheme::chaikin()),
            Just(CurveScheme::cubic_bspline()),
            (-0.2f64..0.2).prop_map(|w| CurveScheme::four_point(w).expect("tension in range")),
            (0.0f64..0.2).prop_map(|g| CurveScheme::combined(g / 2.0 - 1.0 / 16.0, g).expect("C2 line converges")),
            (arb_rule(), arb_rule(), any::<bool>()).prop_map(|(even, odd, primal)| {
                if primal {
                    CurveScheme::primal("user primal", even, odd).expect("named")
                } else {
                    CurveScheme::dual("user dual", even, odd).expect("named")
                }
            }),
        ]
    }

    fn arb_topology() -> impl Strategy<Value = Topology> {
        prop_oneof![
            Just(Topology::Closed),
            Just(Topology::Open(EndRule::Reflect)),
            Just(Topology::Open(EndRule::Repeat))
        ]
    }

    fn bits<P: CurvePoint>(points: &[P]) -> Vec<u64> {
        points.iter().flat_map(|p| (0..P::DIM).map(|a| p.coord(a).to_bits())).collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        /// The fused path equals the level-by-level one bit for bit, for any block size.
        #[test]
        fn fused_equals_level_by_level(
            scheme in arb_scheme(),
            topology in arb_topology(),
            raw in prop::collection::vec((-10.0f64..10.0, -10.0f64..10.0, -10.0f64..10.0), 3..24),
            levels in 0u32..6,
            block in 1usize..40,
        ) {
            prop_assume!(raw.len() >= scheme.min_points(topology));
            let planar: Vec<[f64; 2]> = raw.iter().map(|&(x, y, _)| [x, y]).collect();
            let (mut fused, mut reference) = (Vec::new(), Vec::new());
            let mut refiner = Refiner::new();
            refiner.refine_fused(&scheme, &planar, topology, levels, &mut fused, block);
            refiner.refine_levelwise(&scheme, &planar, topology, levels, &mut reference);
            prop_assert_eq!(fused.len(), scheme.refined_len(planar.len(), topology, levels));
            prop_assert_eq!(bits(&fused), bits(&reference));
            // The public entry point (default block size) and another point type.
            let spatial: Vec<DVec3> = raw.iter().map(|&(x, y, z)| DVec3::new(x, y, z)).collect();
            let (mut fused3, mut reference3) = (Vec::new(), Vec::new());
            let mut refiner3 = Refiner::new();
            refiner3.refine_into(&scheme, &spatial, topology, levels, &mut fused3).expect("valid input");
            refiner3.refine_levelwise(&scheme, &spatial, topology, levels, &mut reference3);
            prop_assert_eq!(bits(&fused3), bits(&reference3));
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// Symmetric vertex rules keep reflected end points bit for bit, at every level
        /// (the framework too, whatever its flags).
        #[test]
        fn reflected_end_points_are_kept_exactly(
            raw in prop::collection::vec((-10.0f64..10.0, -10.0f64..10.0, any::<bool>()), 4..20),
            levels in 1u32..7,
            gamma in 0.0f64..0.2,
        ) {
            let points: Vec<[f64; 2]> = raw.iter().map(|&(x, y, _)| [x, y]).collect();
            let flags: Vec<bool> = raw.iter().map(|&(_, _, flag)| flag).collect();
            let topology = Topology::Open(EndRule::Reflect);
            let (first, last) = (points[0], points[points.len() - 1]);
            for scheme in [
                CurveScheme::cubic_bspline(),
                CurveScheme::combined(gamma / 2.0 - 1.0 / 16.0, gamma).expect("C2 line converges"),
            ] {
                prop_assert!(scheme.reflect_keeps_ends());
                let fine = scheme.refine(&points, topology, levels).expect("valid input");
                prop_assert_eq!(bits(&[fine[0], fine[fine.len() - 1]]), bits(&[first, last]));
            }
            for mode in [crate::VirtualPoints::SeedCompatible, crate::VirtualPoints::ExactGlobal] {
                let framework = crate::Framework::published().with_mode(mode);
                if let Ok(fine) = framework.refine(&points, &flags, topology, levels) {
                    prop_assert_eq!(bits(&[fine[0], fine[fine.len() - 1]]), bits(&[first, last]));
                }
            }
        }
    }

    /// Large outputs are split over the worker threads: 1, 2 and 3 workers (runs of whole
    /// blocks, the last one shorter) give the level-by-level result bit for bit.
    #[test]
    fn any_thread_count_gives_the_same_bits() {
        let points: Vec<[f64; 2]> = (0..301).map(|k| [(k as f64 * 0.37).sin(), (k as f64 * 0.11).cos()]).collect();
        for scheme in [CurveScheme::cubic_bspline(), CurveScheme::four_point(0.0625).unwrap()] {
            for topology in [Topology::Closed, Topology::Open(EndRule::Reflect)] {
                let mut reference = Vec::new();
                Refiner::new().refine_levelwise(&scheme, &points, topology, 10, &mut reference);
                assert!(reference.len() > 3 * PARALLEL_MIN_POINTS);
                for threads in [1, 2, 3] {
                    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                    let mut refiner = Refiner::new();
                    let mut out = Vec::new();
                    pool.install(|| refiner.refine_into(&scheme, &points, topology, 10, &mut out)).unwrap();
                    assert_eq!(refiner.spare.len(), threads - 1);
                    assert_eq!(bits(&out), bits(&reference), "{} {topology:?} on {threads} threads", scheme.name());
                }
            }
        }
    }

    #[test]
    fn blocks_of_a_long_polygon_join_seamlessly() {
        let points: Vec<[f64; 2]> = (0..300).map(|k| [(k as f64 * 0.37).sin(), (k as f64 * 0.11).cos()]).collect();
        for scheme in [CurveScheme::chaikin(), CurveScheme::cubic_bspline(), CurveScheme::four_point(0.0625).unwrap()] {
            for topology in [Topology::Closed, Topology::Open(EndRule::Reflect), Topology::Open(EndRule::Repeat)] {
                let (mut fused, mut reference) = (Vec::new(), Vec::new());
                let mut refiner = Refiner::new();
                refiner.refine_into(&scheme, &points, topology, 7, &mut fused).unwrap();
                refiner.refine_levelwise(&scheme, &points, topology, 7, &mut reference);
                assert!(fused.len() > 2 * block_len::<[f64; 2]>());
                assert_eq!(bits(&fused), bits(&reference), "{} {topology:?}", scheme.name());
                refiner.refine_fused(&scheme, &points, topology, 7, &mut fused, 999);
                assert_eq!(bits(&fused), bits(&reference), "{} {topology:?}, 999-point blocks", scheme.name());
            }
        }
    }

    #[test]
    fn too_many_levels_fail_before_any_work() {
        use crate::{Framework, MAX_REFINED_POINTS};
        let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        // Closed: 4 * 2^levels points; 2^31 fit, 2^32 do not.
        let chaikin = CurveScheme::chaikin();
        assert_eq!(chaikin.checked_refined_len(4, Topology::Closed, 29), Ok(1 << 31));
        for levels in [30, 63, 64, 200, u32::MAX] {
            let error = chaikin.refine(&square, Topology::Closed, levels).unwrap_err();
            assert_eq!(error, CurveError::TooLarge { points: 4, levels, max: MAX_REFINED_POINTS }, "{levels}");
            let flags = [true, false, false, false];
            for framework in
                [Framework::published(), Framework::published().with_mode(crate::VirtualPoints::ExactGlobal)]
            {
                let error = framework.refine(&square, &flags, Topology::Closed, levels).unwrap_err();
                assert!(matches!(error, CurveError::TooLarge { points: 4, .. }), "{error}");
            }
        }
        // Open primal: 2^levels + 1 points from two.
        let bspline = CurveScheme::cubic_bspline();
        assert_eq!(bspline.checked_refined_len(2, Topology::open(), 31), Ok((1 << 31) + 1));
        assert!(bspline.refine(&square[..2], Topology::open(), 32).is_err());
        // The length itself saturates, and stops early where it cannot grow.
        assert_eq!(chaikin.refined_len(4, Topology::Closed, u32::MAX), usize::MAX);
        assert_eq!(bspline.refined_len(1, Topology::open(), u32::MAX), 1);
        assert_eq!(chaikin.refined_len(0, Topology::Closed, u32::MAX), 0);
    }
}
