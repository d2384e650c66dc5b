//! Rendering attractors (ALGORITHMS.md §15.2): the deterministic algorithm, the chaos game,
//! anti-aliased density images and PNG output.
//!
//! # Determinism
//! Both algorithms run in parallel with `rayon` and give **bit-identical results whatever
//! the thread count**:
//! * the deterministic algorithm computes each output point by the same sequence of map
//!   applications (tasks own disjoint, fixed output ranges);
//! * the chaos game is cut into fixed chunks of [`CHAOS_CHUNK`] points; chunk c draws from
//!   its own ChaCha8 stream (`seed`, stream c), starts at the fixed point of map 0 and
//!   discards `burn_in` iterates. The output depends only on (IFS, points, seed, burn-in,
//!   probabilities), not on the scheduling;
//! * densities are accumulated in integers: each point splats bilinear weights quantized to
//!   1/256 that sum to exactly 256, so the summation order cannot change the result.

use std::path::Path;

use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::error::{IfsError, Result, check_finite};
use crate::ifs::Ifs;

/// Points per chaos-game chunk (each chunk has its own random stream and burn-in).
pub const CHAOS_CHUNK: usize = 1 << 14;

/// Most deterministic levels. With two or more maps the point budget binds long before;
/// this bounds the work of a single map (`K = 1`), whose point count never grows.
pub const MAX_LEVELS: u32 = 4096;

/// Most burn-in iterates per chaos-game chunk: 65536 reach 1e-19 relative even for a
/// contraction of 0.9993, and the bound keeps the per-chunk work finite.
pub const MAX_BURN_IN: u32 = 1 << 16;

/// How the chaos game chooses its maps.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Probabilities {
    /// `p_i ∝ |det(linear part of map i)|`, each floored at 1 % of the largest (so that
    /// singular maps, like the fern's stem, still get visited). The default.
    #[default]
    Determinant,
    /// `p_i = 1/K`.
    Uniform,
    /// Given weights (normalized; must be non-negative, finite, not all zero, one per map).
    Custom(Vec<f64>),
}

/// Parameters of the random-iteration algorithm (chaos game).
#[derive(Debug, Clone, PartialEq)]
pub struct ChaosGame {
    /// Number of points produced.
    pub points: usize,
    /// Seed of the random streams.
    pub seed: u64,
    /// Iterates discarded at the start of each chunk (`B ≥ ln(tol/diam)/ln(contraction)`;
    /// 64 gives 1e-19 relative for a contraction of 1/2, 2e-10 for the Lévy curve's 0.707).
    pub burn_in: u32,
    /// Map probabilities.
    pub probabilities: Probabilities,
}

impl Default for ChaosGame {
    fn default() -> Self {
        Self { points: 1 << 20, seed: 0, burn_in: 64, probabilities: Probabilities::Determinant }
    }
}

/// Cumulative thresholds in units of 2^-32: map i is chosen when the random u32 falls in
/// `[thresholds[i-1], thresholds[i])`.
fn thresholds<I: Ifs + ?Sized>(ifs: &I, probabilities: &Probabilities) -> Result<Vec<u64>> {
    let k = ifs.map_count();
    let weights = match probabilities {
        Probabilities::Uniform => vec![1.0; k],
        Probabilities::Determinant => {
            let dets = ifs.determinants();
            let max = dets.iter().copied().fold(0.0, f64::max);
            if max > 0.0 && max.is_finite() { dets.iter().map(|d| d.max(0.01 * max)).collect() } else { vec![1.0; k] }
        }
        Probabilities::Custom(weights) => {
            if weights.len() != k {
                return Err(IfsError::ParameterOutOfRange {
                    name: "probabilities",
                    value: format!("{} weights", weights.len()),
                    reason: "need one weight per map",
                });
            }
            // The sum normalizes the weights, so it must be finite too (f64::MAX twice is not).
            let sum = weights.iter().sum::<f64>();
            if weights.iter().any(|w| !(w.is_finite() && *w >= 0.0)) || !(sum > 0.0 && sum.is_finite()) {
                return Err(IfsError::ParameterOutOfRange {
                    name: "probabilities",
                    value: format!("{weights:?}"),
                    reason: "weights must be finite, non-negative, not all zero, with a finite sum",
                });
            }
            weights.clone()
        }
    };
    let total: f64 = weights.iter().sum();
    let mut acc = 0.0;
    Ok(weights
        .iter()
        .map(|w| {
            acc += w / total;
            (acc * 4_294_967_296.0).round().min(4_294_967_296.0) as u64
        })
        .collect())
}

#[inline]
fn choose(thresholds: &[u64], r: u32) -> usize {
    let r = u64::from(r);
    let mut i = 0;
    while i + 1 < thresholds.len() && r >= thresholds[i] {
        i += 1;
    }
    i
}

fn domain_error<I: Ifs + ?Sized>(ifs: &I, index: usize, map: usize, state: &[f64]) -> IfsError {
    IfsError::Domain {
        index,
        value: format!("{:?}", ifs.point(state)),
        what: format!("map {map}"),
        domain: if ifs.domain().is_empty() { "the maps' domain" } else { ifs.domain() },
    }
}

/// True when the three coordinates are finite. One branch instead of three: `x - x` is 0
/// for every finite x and NaN for NaN and ±inf, and NaN spreads through the sum. Called
/// once per rendered point, in the renderers' inner loops.
#[inline(always)]
#[allow(clippy::eq_op)] // x - x is the point: it is not 0 for NaN and ±inf
fn is_finite_point(p: &[f64; 3]) -> bool {
    (p[0] - p[0]) + (p[1] - p[1]) + (p[2] - p[2]) == 0.0
}

/// The error for a rendered point that is not finite (kept out of line: the inner loops
/// only pay for the test).
#[cold]
#[inline(never)]
fn diverged(index: usize, iteration: u64, point: [f64; 3]) -> IfsError {
    IfsError::Diverged { index, iteration, value: format!("{point:?}") }
}

/// Resizes `points` to `count` entries, as an error rather than an abort when the list
/// does not fit in memory (a generous budget or point count is not memory).
fn resize_points(points: &mut Vec<[f64; 3]>, count: usize) -> Result<()> {
    points.clear();
    points
        .try_reserve_exact(count)
        .map_err(|_| IfsError::TooManyPoints { points: count, bytes: count as u128 * size_of::<[f64; 3]>() as u128 })?;
    points.resize(count, [0.0; 3]);
    Ok(())
}

/// Number of points of `levels` deterministic levels from `starts` start states (saturating).
fn deterministic_count(starts: usize, maps: usize, levels: u32) -> u128 {
    let mut n = starts as u128;
    for _ in 0..levels {
        // Stop once the count can no longer change: no walk through u32::MAX levels.
        if n == 0 || n == u128::MAX || maps == 1 {
            break;
        }
        n = n.saturating_mul(maps as u128);
    }
    n
}

/// The deterministic algorithm (ALGORITHMS.md §15.2): `A_0` = the start states,
/// `A_{k+1} = ∪_i f_i(A_k)`; returns the points of `A_levels`, duplicates included.
///
/// `start` holds concatenated states (`None`: [`Ifs::default_start`], i.e. the control
/// points). Output order: start state, then the word `v_1 … v_k` in lexicographic order,
/// where `v_1` is the map applied first: point = `f_{v_k}(… f_{v_1}(s))`. For the
/// barycentric form that is row `s` of `S_{v_1} ⋯ S_{v_k} P`.
///
/// # Errors
/// [`IfsError::BudgetExceeded`] when `starts · K^levels > budget`;
/// [`IfsError::ParameterOutOfRange`] when `start` is empty or not a whole number of states,
/// or for more than [`MAX_LEVELS`] levels;
/// [`IfsError::NotFinite`] for a NaN or infinite start entry (also when the IFS's default
/// start is not finite, e.g. a nonlinear transform that overflows);
/// [`IfsError::TooManyPoints`] when the points within the budget cannot be allocated;
/// [`IfsError::Domain`] when a nonlinear map leaves its domain;
/// [`IfsError::Diverged`] at the first output point that is not finite (maps that are not
/// contractive, e.g. an affine map scaling by 10 iterated for hundreds of levels), instead of
/// returning NaN or infinite points.
///
/// ```
/// use ifs_nonlinear::{BarycentricIfs, bezier_split, deterministic_points};
/// let ifs = BarycentricIfs::new(&bezier_split(2, 0.5)?, &[[0.0, 0.0], [1.0, 2.0], [3.0, 0.0]])?;
/// let points = deterministic_points(&ifs, None, 4, 1 << 20)?;
/// assert_eq!(points.len(), 3 * 16);
/// # Ok::<(), ifs_nonlinear::IfsError>(())
/// ```
pub fn deterministic_points<I: Ifs + ?Sized>(
    ifs: &I,
    start: Option<&[f64]>,
    levels: u32,
    budget: usize,
) -> Result<Vec<[f64; 3]>> {
    let mut points = Vec::new();
    deterministic_into(ifs, start, levels, budget, &mut points)?;
    Ok(points)
}

/// [`deterministic_points`] writing into a reusable buffer (resized to the output, every
/// entry overwritten); returns the number of map applications performed.
///
/// # Errors
/// As [`deterministic_points`].
///
/// ```
/// use ifs_nonlinear::{AffineIfs, IfsError, deterministic_into, deterministic_points, sierpinski};
/// let ifs = AffineIfs::from_rule(&sierpinski(), &[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])?;
/// let mut buffer = Vec::new();
/// for levels in [5, 3] {
///     let applications = deterministic_into(&ifs, None, levels, 1 << 12, &mut buffer)?;
///     assert_eq!(buffer, deterministic_points(&ifs, None, levels, 1 << 12)?);
///     assert!(applications >= buffer.len() as u64); // each point is at least one map application
/// }
/// // 3 start points · 3^8 words = 19683 points do not fit a budget of 1000.
/// let too_many = deterministic_into(&ifs, None, 8, 1000, &mut buffer);
/// assert!(matches!(too_many, Err(IfsError::BudgetExceeded { needed: 19683, .. })));
/// # Ok::<(), IfsError>(())
/// ```
pub fn deterministic_into<I: Ifs + ?Sized>(
    ifs: &I,
    start: Option<&[f64]>,
    levels: u32,
    budget: usize,
    points: &mut Vec<[f64; 3]>,
) -> Result<u64> {
    let n = ifs.state_len();
    let k = ifs.map_count();
    let default_start;
    let given = start.is_some();
    let start = match start {
        Some(s) => s,
        None => {
            default_start = ifs.default_start();
            &default_start
        }
    };
    if start.is_empty() || start.len() % n != 0 {
        return Err(IfsError::ParameterOutOfRange {
            name: "start",
            value: format!("{} numbers", start.len()),
            reason: "the start set must be a non-empty list of whole states",
        });
    }
    // A NaN start state would come out as NaN points: name it instead.
    if let Some(position) = start.iter().position(|v| !v.is_finite()) {
        let which = if given { "start state" } else { "default start state (from the IFS)" };
        return Err(IfsError::NotFinite {
            what: format!("{which} {}, entry {}", position / n, position % n),
            value: start[position],
        });
    }
    let starts = start.len() / n;
    let needed = deterministic_count(starts, k, levels);
    if needed > budget as u128 {
        return Err(IfsError::BudgetExceeded { levels, needed, budget });
    }
    if levels > MAX_LEVELS {
        return Err(IfsError::ParameterOutOfRange {
            name: "levels",
            value: levels.to_string(),
            reason: "at most 4096 deterministic levels",
        });
    }
    let total = needed as usize;
    // Split the words by a prefix of `split` letters so that there are enough tasks.
    let mut split = 0;
    while split < levels && starts * k.pow(split) < 256 {
        split += 1;
    }
    let rest = levels - split;
    let leaves = k.pow(rest);
    // Every entry is overwritten below: a reused buffer of the right length is not re-zeroed.
    if points.len() != total {
        resize_points(points, total)?;
    }
    let prefixes = k.pow(split);
    let results: Vec<Result<u64>> = points
        .par_chunks_mut(leaves)
        .enumerate()
        .map(|(task, out)| {
            let (start_index, mut prefix) = (task / prefixes, task % prefixes);
            let first_index = task * leaves;
            let mut applications = 0u64;
            // The task's prefix: `split` letters, most significant first = first applied.
            let mut letters = vec![0usize; split as usize];
            for d in (0..split as usize).rev() {
                letters[d] = prefix % k;
                prefix /= k;
            }
            let capacity = (leaves / k).max(1) * n;
            let mut current = Vec::with_capacity(capacity);
            let mut next = Vec::with_capacity(capacity);
            let mut scratch = vec![0.0; n];
            current.extend_from_slice(&start[start_index * n..(start_index + 1) * n]);
            for &letter in &letters {
                if !ifs.apply(letter, &current, &mut scratch) {
                    return Err(domain_error(ifs, first_index, letter, &current));
                }
                current.copy_from_slice(&scratch);
                applications += 1;
            }
            if rest == 0 {
                let point = ifs.point(&current);
                if !is_finite_point(&point) {
                    return Err(diverged(first_index, u64::from(levels), point));
                }
                out[0] = point;
                return Ok(applications);
            }
            // The remaining levels breadth first: level l holds its k^l states in word order
            // (first letter most significant), so child i k + j of state i is f_j(state i),
            // which is already the output order. Each point is computed by the same map
            // applications as depth first, so the results do not depend on this layout.
            for level in 1..rest {
                let below = k.pow(rest - level); // output points under each state of this level
                let parents = current.len() / n;
                next.clear();
                next.resize(parents * k * n, 0.0);
                for (i, (parent, children)) in current.chunks_exact(n).zip(next.chunks_exact_mut(k * n)).enumerate() {
                    for (map, child) in children.chunks_exact_mut(n).enumerate() {
                        if !ifs.apply(map, parent, child) {
                            return Err(domain_error(ifs, first_index + (i * k + map) * below, map, parent));
                        }
                    }
                }
                applications += (parents * k) as u64;
                std::mem::swap(&mut current, &mut next);
            }
            // The last level straight into the output.
            for (i, (parent, slots)) in current.chunks_exact(n).zip(out.chunks_exact_mut(k)).enumerate() {
                for (map, slot) in slots.iter_mut().enumerate() {
                    if !ifs.apply(map, parent, &mut scratch) {
                        return Err(domain_error(ifs, first_index + i * k + map, map, parent));
                    }
                    let point = ifs.point(&scratch);
                    if !is_finite_point(&point) {
                        return Err(diverged(first_index + i * k + map, u64::from(levels), point));
                    }
                    *slot = point;
                }
            }
            applications += out.len() as u64;
            Ok(applications)
        })
        .collect();
    let mut applications = 0;
    for r in results {
        applications += r?;
    }
    Ok(applications)
}

/// Runs one chaos-game chunk, calling `sink(index_in_chunk, point)` for each kept point.
fn chaos_chunk<I: Ifs + ?Sized>(
    ifs: &I,
    game: &ChaosGame,
    thresholds: &[u64],
    start: &[f64],
    chunk: usize,
    count: usize,
    mut sink: impl FnMut([f64; 3]),
) -> Result<()> {
    let n = ifs.state_len();
    let mut rng = ChaCha8Rng::seed_from_u64(game.seed);
    rng.set_stream(chunk as u64);
    let mut a = start.to_vec();
    let mut b = vec![0.0; n];
    let first = chunk * CHAOS_CHUNK;
    for step in 0..(game.burn_in as usize + count) {
        let map = choose(thresholds, rng.next_u32());
        if !ifs.apply(map, &a, &mut b) {
            return Err(domain_error(ifs, first + step.saturating_sub(game.burn_in as usize), map, &a));
        }
        std::mem::swap(&mut a, &mut b);
        if step >= game.burn_in as usize {
            let point = ifs.point(&a);
            // Diverging maps (not contractive) would otherwise fill the list with inf/NaN
            // or, in a density, silently drop every point.
            if !is_finite_point(&point) {
                return Err(diverged(first + step - game.burn_in as usize, step as u64 + 1, point));
            }
            sink(point);
        }
    }
    Ok(())
}

/// Applications of map 0 that move the chaos game's start state onto the attractor.
const CHAOS_START_STEPS: u32 = 128;

/// Chaos-game start state: the default start's first state moved towards the fixed point
/// of map 0 (which lies on the attractor).
///
/// # Errors
/// [`IfsError::Domain`]; [`IfsError::Diverged`] (point 0) when map 0 drives the start state
/// out of the finite numbers (it is not contractive).
fn chaos_start<I: Ifs + ?Sized>(ifs: &I) -> Result<Vec<f64>> {
    let n = ifs.state_len();
    let mut a = ifs.default_start()[..n].to_vec();
    let mut b = vec![0.0; n];
    for _ in 0..CHAOS_START_STEPS {
        if !ifs.apply(0, &a, &mut b) {
            return Err(domain_error(ifs, 0, 0, &a));
        }
        std::mem::swap(&mut a, &mut b);
    }
    let point = ifs.point(&a);
    if !is_finite_point(&point) {
        return Err(diverged(0, u64::from(CHAOS_START_STEPS), point));
    }
    Ok(a)
}

fn check_game(game: &ChaosGame) -> Result<()> {
    if game.points == 0 {
        return Err(IfsError::ParameterOutOfRange {
            name: "points",
            value: "0".into(),
            reason: "need at least one point",
        });
    }
    if game.burn_in > MAX_BURN_IN {
        return Err(IfsError::ParameterOutOfRange {
            name: "burn_in",
            value: game.burn_in.to_string(),
            reason: "at most 65536 iterates per chunk",
        });
    }
    Ok(())
}

/// The chaos game (random iteration, ALGORITHMS.md §15.2): `game.points` points of the
/// attractor, in parallel, deterministic for a given seed whatever the thread count (see
/// the [module docs](self)).
///
/// # Errors
/// [`IfsError::ParameterOutOfRange`] for zero points or bad probabilities;
/// [`IfsError::TooManyPoints`] when the list of `game.points` points cannot be allocated
/// (before any iteration);
/// [`IfsError::Domain`] when a nonlinear map leaves its domain;
/// [`IfsError::Diverged`] at the first point that is not finite: the maps are not
/// contractive (e.g. affine maps scaling by 10), so the iterates run off to infinity.
///
/// ```
/// use ifs_nonlinear::{AffineIfs, ChaosGame, chaos_points, sierpinski};
/// let ifs = AffineIfs::from_rule(&sierpinski(), &[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])?;
/// let points = chaos_points(&ifs, &ChaosGame { points: 1000, seed: 7, ..ChaosGame::default() })?;
/// assert!(points.iter().all(|p| p[0] >= -1e-12 && p[1] >= -1e-12 && p[0] + p[1] <= 1.0 + 1e-12));
/// # Ok::<(), ifs_nonlinear::IfsError>(())
/// ```
pub fn chaos_points<I: Ifs + ?Sized>(ifs: &I, game: &ChaosGame) -> Result<Vec<[f64; 3]>> {
    check_game(game)?;
    let thresholds = thresholds(ifs, &game.probabilities)?;
    let start = chaos_start(ifs)?;
    // Asked for, not given: a count beyond memory is an error, not an abort.
    let mut points = Vec::new();
    resize_points(&mut points, game.points)?;
    points
        .par_chunks_mut(CHAOS_CHUNK)
        .enumerate()
        .map(|(chunk, out)| {
            let count = out.len();
            let mut slots = out.iter_mut();
            chaos_chunk(ifs, game, &thresholds, &start, chunk, count, |p| {
                *slots.next().expect("internal: chunk sized to its output") = p;
            })
        })
        .collect::<Vec<Result<()>>>()
        .into_iter()
        .collect::<Result<()>>()?;
    Ok(points)
}

/// The chaos game straight into a density image (no point list is kept).
///
/// # Errors
/// As [`chaos_points`] (a diverging game is an error, not an empty image), and as
/// [`Density::from_points`] for a hand-built `canvas` that [`Canvas::new`] would refuse.
///
/// ```
/// use ifs_nonlinear::{AffineIfs, Canvas, ChaosGame, View, chaos_density, sierpinski};
/// let ifs = AffineIfs::from_rule(&sierpinski(), &[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])?;
/// let canvas = Canvas::new(64, 64, View::new([-0.1, -0.1], [1.1, 1.1])?)?;
/// let density = chaos_density(&ifs, &ChaosGame { points: 10_000, ..ChaosGame::default() }, &canvas)?;
/// assert_eq!(density.total_points(), 10_000.0); // every point lands inside the view
/// # Ok::<(), ifs_nonlinear::IfsError>(())
/// ```
pub fn chaos_density<I: Ifs + ?Sized>(ifs: &I, game: &ChaosGame, canvas: &Canvas) -> Result<Density> {
    check_game(game)?;
    let thresholds = thresholds(ifs, &game.probabilities)?;
    let start = chaos_start(ifs)?;
    let chunks = game.points.div_ceil(CHAOS_CHUNK);
    let counts = accumulate_in_groups(canvas, chunks, |chunk, counts| {
        let count = CHAOS_CHUNK.min(game.points - chunk * CHAOS_CHUNK);
        chaos_chunk(ifs, game, &thresholds, &start, chunk, count, |p| canvas.splat(counts, p))
    })?;
    Ok(Density { width: canvas.width, height: canvas.height, counts })
}

/// Runs `work(chunk, counts)` for chunks `0..chunks`, in one contiguous group of chunks per
/// thread, each group with its own accumulation buffer, then adds the buffers. Integer
/// sums make the result independent of the grouping (and so of the thread count), and one
/// buffer per thread (not per chunk) keeps the zeroing and merging cost small.
///
/// # Errors
/// The canvas check of [`Canvas::pixel_count`] (before any allocation), then the first
/// error of `work` in chunk order.
fn accumulate_in_groups(
    canvas: &Canvas,
    chunks: usize,
    work: impl Fn(usize, &mut [u64]) -> Result<()> + Sync,
) -> Result<Vec<u64>> {
    let pixels = canvas.pixel_count()?;
    let groups = rayon::current_num_threads().clamp(1, chunks.max(1));
    let buffers: Vec<Result<Vec<u64>>> = (0..groups)
        .into_par_iter()
        .map(|g| {
            let mut counts = vec![0u64; pixels];
            for chunk in g * chunks / groups..(g + 1) * chunks / groups {
                work(chunk, &mut counts)?;
            }
            Ok(counts)
        })
        .collect();
    let mut total: Option<Vec<u64>> = None;
    for buffer in buffers {
        let buffer = buffer?;
        match total.as_mut() {
            None => total = Some(buffer),
            Some(t) => t.iter_mut().zip(&buffer).for_each(|(x, y)| *x += y),
        }
    }
    Ok(total.unwrap_or_else(|| vec![0; pixels]))
}

/// A world-space rectangle shown by the image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    /// Lower-left corner (x, y).
    pub min: [f64; 2],
    /// Upper-right corner.
    pub max: [f64; 2],
}

impl View {
    /// The rectangle `[min, max]`.
    ///
    /// # Errors
    /// [`IfsError::Render`] for an empty or non-finite rectangle.
    ///
    /// ```
    /// use ifs_nonlinear::View;
    /// let view = View::new([-1.0, 0.0], [1.0, 2.0])?;
    /// assert_eq!((view.min, view.max), ([-1.0, 0.0], [1.0, 2.0]));
    /// assert!(View::new([0.0, 0.0], [0.0, 1.0]).is_err()); // zero width
    /// assert!(View::new([0.0, 0.0], [1.0, f64::NAN]).is_err());
    /// # Ok::<(), ifs_nonlinear::IfsError>(())
    /// ```
    pub fn new(min: [f64; 2], max: [f64; 2]) -> Result<Self> {
        if !(min.iter().chain(&max).all(|v| v.is_finite()) && max[0] > min[0] && max[1] > min[1]) {
            return Err(IfsError::Render(format!("empty or non-finite view {min:?}..{max:?}")));
        }
        Ok(Self { min, max })
    }

    /// The smallest rectangle with the aspect ratio `width:height` that holds the projected
    /// points with a relative `margin` on each side (degenerate extents are widened).
    ///
    /// # Errors
    /// [`IfsError::Render`] when there is no finite point; [`IfsError::NotFinite`] for a NaN
    /// or infinite projection angle (it would make every point NaN).
    ///
    /// ```
    /// use ifs_nonlinear::{Projection, View};
    /// // The unit square in a 2:1 image without margin: widened about its centre to [-0.5, 1.5] × [0, 1].
    /// let square = [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0]];
    /// assert_eq!(View::fit(&square, Projection::Xy, 200, 100, 0.0)?, View::new([-0.5, 0.0], [1.5, 1.0])?);
    /// assert!(View::fit(&[], Projection::Xy, 200, 100, 0.0).is_err()); // nothing to fit
    /// # Ok::<(), ifs_nonlinear::IfsError>(())
    /// ```
    pub fn fit(points: &[[f64; 3]], projection: Projection, width: u32, height: u32, margin: f64) -> Result<Self> {
        projection.check()?;
        let mut min = [f64::INFINITY; 2];
        let mut max = [f64::NEG_INFINITY; 2];
        for p in points {
            let q = projection.project(*p);
            if q[0].is_finite() && q[1].is_finite() {
                for k in 0..2 {
                    min[k] = min[k].min(q[k]);
                    max[k] = max[k].max(q[k]);
                }
            }
        }
        if !min[0].is_finite() {
            return Err(IfsError::Render("no finite point to fit the view to".into()));
        }
        let mut size = [max[0] - min[0], max[1] - min[1]];
        // Degenerate extents (one point, a segment) are widened relative to the points'
        // magnitude, so that the view does not depend on the scale (an absolute floor
        // of 1e-9 drew a cloud of extent 1e-12 as one dot); points all at the origin
        // get a unit view.
        let magnitude = min.iter().chain(&max).fold(0.0f64, |m, v| m.max(v.abs()));
        let extent = match size[0].max(size[1]).max(1e-9 * magnitude) {
            0.0 => 1.0,
            extent => extent,
        };
        let aspect = f64::from(width.max(1)) / f64::from(height.max(1));
        size = [size[0].max(extent * 1e-3), size[1].max(extent * 1e-3)];
        let grow = 1.0 + 2.0 * margin.max(0.0);
        let (mut w, mut h) = (size[0] * grow, size[1] * grow);
        if w / h < aspect {
            w = h * aspect
        } else {
            h = w / aspect
        }
        let centre = [(min[0] + max[0]) / 2.0, (min[1] + max[1]) / 2.0];
        Self::new([centre[0] - w / 2.0, centre[1] - h / 2.0], [centre[0] + w / 2.0, centre[1] + h / 2.0])
    }
}

/// How 3D points are drawn (2D points ignore it except through their z = 0).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Projection {
    /// Drop z.
    #[default]
    Xy,
    /// Orthographic view from the direction given by azimuth (about z) and elevation, in
    /// radians.
    Orbit {
        /// Rotation about the z axis.
        azimuth: f64,
        /// Angle above the xy plane.
        elevation: f64,
    },
}

impl Projection {
    /// Checks the angles of [`Projection::Orbit`]: a NaN or infinite angle projects every
    /// point to NaN, which would leave an image silently empty.
    ///
    /// # Errors
    /// [`IfsError::NotFinite`] naming the angle.
    ///
    /// ```
    /// use ifs_nonlinear::{IfsError, Projection};
    /// assert!(Projection::Orbit { azimuth: 0.6, elevation: 0.45 }.check().is_ok());
    /// let err = Projection::Orbit { azimuth: f64::NAN, elevation: 0.0 }.check().unwrap_err();
    /// assert!(matches!(err, IfsError::NotFinite { .. }) && err.to_string().contains("azimuth"));
    /// ```
    pub fn check(&self) -> Result<()> {
        if let Projection::Orbit { azimuth, elevation } = *self {
            check_finite(azimuth, || "projection azimuth".into())?;
            check_finite(elevation, || "projection elevation".into())?;
        }
        Ok(())
    }

    /// Projects a point to the image plane.
    ///
    /// ```
    /// use ifs_nonlinear::Projection;
    /// assert_eq!(Projection::Xy.project([1.0, 2.0, 3.0]), [1.0, 2.0]);
    /// // Seen from the front (azimuth 0, elevation 0), the image plane is (x, z).
    /// assert_eq!(Projection::Orbit { azimuth: 0.0, elevation: 0.0 }.project([1.0, 2.0, 3.0]), [1.0, 3.0]);
    /// ```
    #[inline]
    pub fn project(&self, p: [f64; 3]) -> [f64; 2] {
        match *self {
            Projection::Xy => [p[0], p[1]],
            Projection::Orbit { azimuth, elevation } => {
                let (sa, ca) = azimuth.sin_cos();
                let (se, ce) = elevation.sin_cos();
                let x = ca * p[0] + sa * p[1];
                let depth_axis = -sa * p[0] + ca * p[1];
                [x, ce * p[2] - se * depth_axis]
            }
        }
    }
}

/// Image size, view and projection.
///
/// The fields are public, so a canvas can be built without [`Canvas::new`]; the renderers
/// ([`Density::from_points`], [`chaos_density`]) check such a canvas as `new` would before
/// allocating anything (a hand-built `u32::MAX × u32::MAX` canvas is an error, not an abort).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Canvas {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The world rectangle shown.
    pub view: View,
    /// 3D → 2D.
    pub projection: Projection,
}

/// Largest image side accepted.
pub const MAX_IMAGE_SIDE: u32 = 16_384;

/// The image-size rule shared by [`Canvas::new`] and [`Canvas::pixel_count`].
fn check_image_size(width: u32, height: u32) -> Result<()> {
    if !(1..=MAX_IMAGE_SIDE).contains(&width) || !(1..=MAX_IMAGE_SIDE).contains(&height) {
        return Err(IfsError::Render(format!("image size {width}x{height} is not in 1..={MAX_IMAGE_SIDE}")));
    }
    Ok(())
}

/// Checks that every point is finite, naming the first that is not: NaN input is an error,
/// not a point silently left out of the image.
fn check_finite_points(points: &[[f64; 3]]) -> Result<()> {
    match points.iter().position(|p| !is_finite_point(p)) {
        None => Ok(()),
        Some(i) => {
            let k = points[i].iter().position(|v| !v.is_finite()).unwrap_or(0);
            Err(IfsError::NotFinite { what: format!("point {i}, coordinate {k}"), value: points[i][k] })
        }
    }
}

impl Canvas {
    /// A canvas of `width × height` pixels showing `view` (projection [`Projection::Xy`]).
    ///
    /// # Errors
    /// [`IfsError::Render`] for a zero side or one above [`MAX_IMAGE_SIDE`].
    ///
    /// ```
    /// use ifs_nonlinear::{Canvas, Projection, View};
    /// let canvas = Canvas::new(320, 200, View::new([0.0, 0.0], [1.6, 1.0])?)?;
    /// assert_eq!((canvas.width, canvas.height, canvas.projection), (320, 200, Projection::Xy));
    /// assert!(Canvas::new(0, 200, canvas.view).is_err());
    /// # Ok::<(), ifs_nonlinear::IfsError>(())
    /// ```
    pub fn new(width: u32, height: u32, view: View) -> Result<Self> {
        check_image_size(width, height)?;
        Ok(Self { width, height, view, projection: Projection::Xy })
    }

    /// Number of pixels, after the checks of [`Canvas::new`], [`View::new`] and
    /// [`Projection::check`]: the fields are public, and the renderers allocate one counter
    /// per pixel (per thread), so a hand-built canvas is checked before that allocation.
    ///
    /// # Errors
    /// [`IfsError::Render`] for a side of 0 or above [`MAX_IMAGE_SIDE`], or an empty or
    /// non-finite view; [`IfsError::NotFinite`] for a non-finite projection angle.
    ///
    /// ```
    /// use ifs_nonlinear::{Canvas, View};
    /// let canvas = Canvas::new(320, 200, View::new([0.0, 0.0], [1.6, 1.0])?)?;
    /// assert_eq!(canvas.pixel_count()?, 64_000);
    /// // A hand-built canvas that `Canvas::new` would refuse.
    /// assert!(Canvas { width: 100_000, ..canvas }.pixel_count().is_err());
    /// # Ok::<(), ifs_nonlinear::IfsError>(())
    /// ```
    pub fn pixel_count(&self) -> Result<usize> {
        check_image_size(self.width, self.height)?;
        View::new(self.view.min, self.view.max)?;
        self.projection.check()?;
        Ok(self.width as usize * self.height as usize)
    }

    /// The same canvas with another projection.
    ///
    /// ```
    /// use ifs_nonlinear::{Canvas, Density, Projection, View};
    /// let canvas = Canvas::new(8, 8, View::new([0.0, 0.0], [1.0, 1.0])?)?;
    /// let front = canvas.with_projection(Projection::Orbit { azimuth: 0.0, elevation: 0.0 }); // image plane (x, z)
    /// let point = [[0.5, 7.0, 0.5]];
    /// assert_eq!(Density::from_points(&point, &front)?.total_points(), 1.0);
    /// assert_eq!(Density::from_points(&point, &canvas)?.total_points(), 0.0); // (x, y) = (0.5, 7) is off the view
    /// # Ok::<(), ifs_nonlinear::IfsError>(())
    /// ```
    pub fn with_projection(mut self, projection: Projection) -> Self {
        self.projection = projection;
        self
    }

    /// Adds one point with bilinear weights (16 × 16 sub-pixel positions, weights summing
    /// to exactly 256) to `counts`. Points outside the view are dropped.
    #[inline]
    fn splat(&self, counts: &mut [u64], p: [f64; 3]) {
        let q = self.projection.project(p);
        let (w, h) = (self.width as usize, self.height as usize);
        // Position in sixteenths of a pixel, shifted by one pixel so that everything that
        // can touch the image is positive (truncation = floor; no libm calls).
        let sx = (q[0] - self.view.min[0]) * (16.0 * w as f64 / (self.view.max[0] - self.view.min[0])) + 8.5;
        let sy = (self.view.max[1] - q[1]) * (16.0 * h as f64 / (self.view.max[1] - self.view.min[1])) + 8.5;
        // Pixel centres at integer + 1/2: 16 (u - 1/2) + 16 (one-pixel shift) + 1/2 (rounding) = 16 u + 8.5.
        if !(sx >= 0.0 && sy >= 0.0 && sx < 16.0 * (w + 1) as f64 && sy < 16.0 * (h + 1) as f64) {
            return;
        }
        let (qx, qy) = (sx as usize, sy as usize);
        let (ax, ay) = ((qx & 15) as u64, (qy & 15) as u64);
        // Top-left pixel of the 2 x 2 footprint, in shifted coordinates (0 = one pixel left of the image).
        let (ix, iy) = (qx >> 4, qy >> 4);
        let weights = [(16 - ax) * (16 - ay), ax * (16 - ay), (16 - ax) * ay, ax * ay];
        for (corner, weight) in weights.into_iter().enumerate() {
            let (x, y) = (ix + (corner & 1), iy + (corner >> 1));
            // Shifted coordinates 1..=w are the image columns 0..w.
            if weight != 0 && x >= 1 && y >= 1 && x <= w && y <= h {
                counts[(y - 1) * w + (x - 1)] += weight;
            }
        }
    }
}

/// Accumulated point density (units of 1/256 point per pixel), row-major, top row first.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Density {
    width: u32,
    height: u32,
    counts: Vec<u64>,
}

impl Density {
    /// Splats points into a new density image, in parallel (bit-identical for any thread
    /// count: integer accumulation). Points outside the view are left out.
    ///
    /// # Errors
    /// [`IfsError::NotFinite`] naming the first NaN or infinite point; as
    /// [`Canvas::pixel_count`] for a hand-built canvas that [`Canvas::new`] would refuse
    /// (e.g. `u32::MAX` sides, which used to abort allocating).
    ///
    /// ```
    /// use ifs_nonlinear::{Canvas, Density, View};
    /// let canvas = Canvas::new(4, 4, View::new([0.0, 0.0], [1.0, 1.0])?)?;
    /// assert_eq!(Density::from_points(&[[0.5, 0.5, 0.0]], &canvas)?.total_points(), 1.0);
    /// let huge = Canvas { width: u32::MAX, height: u32::MAX, ..canvas };
    /// assert!(Density::from_points(&[[0.5, 0.5, 0.0]], &huge).is_err());
    /// # Ok::<(), ifs_nonlinear::IfsError>(())
    /// ```
    pub fn from_points(points: &[[f64; 3]], canvas: &Canvas) -> Result<Self> {
        check_finite_points(points)?;
        Self::splat_finite_points(points, canvas)
    }

    /// [`from_points`](Self::from_points) for points already checked to be finite.
    fn splat_finite_points(points: &[[f64; 3]], canvas: &Canvas) -> Result<Self> {
        let chunks = points.len().div_ceil(CHAOS_CHUNK);
        let counts = accumulate_in_groups(canvas, chunks, |chunk, counts| {
            let end = ((chunk + 1) * CHAOS_CHUNK).min(points.len());
            points[chunk * CHAOS_CHUNK..end].iter().for_each(|p| canvas.splat(counts, *p));
            Ok(())
        })?;
        Ok(Self { width: canvas.width, height: canvas.height, counts })
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Raw counts in units of 1/256 point.
    ///
    /// ```
    /// use ifs_nonlinear::{Canvas, Density, View};
    /// let canvas = Canvas::new(4, 4, View::new([0.0, 0.0], [1.0, 1.0])?)?;
    /// // A point at the centre of the top-left pixel puts all 256 units there...
    /// assert_eq!(Density::from_points(&[[0.125, 0.875, 0.0]], &canvas)?.counts()[..2], [256, 0]);
    /// // ...one on the border of two pixels, half in each.
    /// assert_eq!(Density::from_points(&[[0.25, 0.875, 0.0]], &canvas)?.counts()[..2], [128, 128]);
    /// # Ok::<(), ifs_nonlinear::IfsError>(())
    /// ```
    pub fn counts(&self) -> &[u64] {
        &self.counts
    }

    /// Sum of all weights, in points (points that landed in the view).
    pub fn total_points(&self) -> f64 {
        self.counts.iter().sum::<u64>() as f64 / 256.0
    }

    /// Tone-maps the density to an RGBA image: intensity `i ∈ [0, 1]` blends `background`
    /// (i = 0) into `ink` (i = 1).
    ///
    /// ```
    /// use ifs_nonlinear::{Canvas, Density, ToneMap, View};
    /// let canvas = Canvas::new(2, 1, View::new([0.0, 0.0], [2.0, 1.0])?)?;
    /// let density = Density::from_points(&[[0.5, 0.5, 0.0]], &canvas)?; // centre of the left pixel
    /// let (ink, paper) = ([200, 0, 0, 255], [255, 255, 255, 255]);
    /// let image = density.to_image(ToneMap::Coverage, ink, paper);
    /// assert_eq!((image.width, image.height, image.rgba), (2, 1, [ink, paper].concat()));
    /// # Ok::<(), ifs_nonlinear::IfsError>(())
    /// ```
    pub fn to_image(&self, tone: ToneMap, ink: [u8; 4], background: [u8; 4]) -> Image {
        let max = self.counts.iter().copied().max().unwrap_or(0) as f64 / 256.0;
        let mut rgba = Vec::with_capacity(self.counts.len() * 4);
        for &c in &self.counts {
            let d = c as f64 / 256.0;
            let i = if max <= 0.0 {
                0.0
            } else {
                match tone {
                    ToneMap::Log => (1.0 + d).ln() / (1.0 + max).ln(),
                    ToneMap::Gamma(g) => (d / max).powf(1.0 / g.max(1e-3)),
                    ToneMap::Coverage => (d.min(1.0)).sqrt(),
                }
            };
            for k in 0..4 {
                let v = f64::from(background[k]) * (1.0 - i) + f64::from(ink[k]) * i;
                rgba.push(v.round().clamp(0.0, 255.0) as u8);
            }
        }
        Image { width: self.width, height: self.height, rgba }
    }
}

/// Density → intensity.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum ToneMap {
    /// `ln(1 + d) / ln(1 + d_max)`: shows the whole dynamic range (the default).
    #[default]
    Log,
    /// `(d / d_max)^(1/γ)`.
    Gamma(f64),
    /// `sqrt(min(d, 1))`: one point per pixel is full ink (good for sparse deterministic sets).
    Coverage,
}

/// An 8-bit RGBA image.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major RGBA bytes, top row first.
    pub rgba: Vec<u8>,
}

impl Image {
    /// Encodes the image as PNG.
    ///
    /// # Errors
    /// [`IfsError::Png`] if the encoder fails.
    ///
    /// ```
    /// let image = ifs_nonlinear::Image { width: 2, height: 1, rgba: vec![0, 0, 0, 255, 255, 255, 255, 255] };
    /// let bytes = image.encode_png()?;
    /// assert_eq!(&bytes[1..4], b"PNG");
    /// # Ok::<(), ifs_nonlinear::IfsError>(())
    /// ```
    pub fn encode_png(&self) -> Result<Vec<u8>> {
        let mut bytes = Vec::new();
        {
            let mut encoder = png::Encoder::new(&mut bytes, self.width, self.height);
            encoder.set_color(png::ColorType::Rgba);
            encoder.set_depth(png::BitDepth::Eight);
            let mut writer = encoder.write_header().map_err(|e| IfsError::Png(e.to_string()))?;
            writer.write_image_data(&self.rgba).map_err(|e| IfsError::Png(e.to_string()))?;
        }
        Ok(bytes)
    }

    /// Writes the image as a PNG file.
    ///
    /// # Errors
    /// [`IfsError::Png`] if encoding or writing fails (the message names the path).
    ///
    /// ```
    /// let image = ifs_nonlinear::Image { width: 1, height: 1, rgba: vec![255, 0, 0, 255] };
    /// let dir = std::env::temp_dir();
    /// let path = dir.join(format!("ifs-nonlinear-write-png-{}.png", std::process::id()));
    /// image.write_png(&path)?;
    /// assert_eq!(std::fs::read(&path).unwrap(), image.encode_png()?);
    /// # std::fs::remove_file(&path).unwrap();
    /// assert!(image.write_png(&dir.join("no-such-directory-ifs-nonlinear").join("x.png")).is_err());
    /// # Ok::<(), ifs_nonlinear::IfsError>(())
    /// ```
    pub fn write_png(&self, path: &Path) -> Result<()> {
        let bytes = self.encode_png()?;
        std::fs::write(path, bytes).map_err(|e| IfsError::Png(format!("{}: {e}", path.display())))
    }
}

/// Renders points to an image in one call: fits the view (2 % margin), splats, tone-maps
/// (black ink on white).
///
/// # Errors
/// [`IfsError::Render`] for a bad size or no point; [`IfsError::NotFinite`] naming the
/// first NaN or infinite point, or a non-finite projection angle.
///
/// ```
/// use ifs_nonlinear::{AffineIfs, Projection, ToneMap, deterministic_points, render_points, sierpinski};
/// let ifs = AffineIfs::from_rule(&sierpinski(), &[[0.0, 0.0], [1.0, 0.0], [0.5, 0.9]])?;
/// let points = deterministic_points(&ifs, None, 6, 1 << 20)?;
/// let image = render_points(&points, 128, 128, Projection::Xy, ToneMap::Coverage)?;
/// assert_eq!(image.rgba.len(), 128 * 128 * 4);
/// # Ok::<(), ifs_nonlinear::IfsError>(())
/// ```
pub fn render_points(
    points: &[[f64; 3]],
    width: u32,
    height: u32,
    projection: Projection,
    tone: ToneMap,
) -> Result<Image> {
    check_finite_points(points)?;
    let view = View::fit(points, projection, width, height, 0.02)?;
    let canvas = Canvas::new(width, height, view)?.with_projection(projection);
    Ok(Density::splat_finite_points(points, &canvas)?.to_image(tone, [0, 0, 0, 255], [255, 255, 255, 255]))
}

/// Summary statistics of a point set, for golden tests that compare with a tolerance.
#[derive(Debug, Clone, PartialEq)]
pub struct PointStats {
    /// Number of points.
    pub count: usize,
    /// Bounding box minimum (x, y, z).
    pub min: [f64; 3],
    /// Bounding box maximum.
    pub max: [f64; 3],
    /// Mean point.
    pub centroid: [f64; 3],
    /// Occupancy of a `grid × grid` subdivision of the xy bounding box, row by row from the
    /// top: one bit per cell (cell occupied by at least one point).
    pub occupancy: Vec<Vec<bool>>,
}

/// Most cells per side of a [`PointStats`] occupancy map (16.8 million cells).
pub const MAX_OCCUPANCY_GRID: usize = 4096;

impl PointStats {
    /// Computes the statistics; `grid` cells per side for the occupancy map.
    ///
    /// ```
    /// let stats = ifs_nonlinear::PointStats::of(&[[0.0, 0.0, 0.0], [1.0, 1.0, 0.0]], 2)?;
    /// assert_eq!(stats.centroid, [0.5, 0.5, 0.0]);
    /// assert_eq!(stats.occupied_cells(), 2);
    /// # Ok::<(), ifs_nonlinear::IfsError>(())
    /// ```
    ///
    /// # Errors
    /// [`IfsError::NotFinite`] naming the first point with a NaN or infinite coordinate
    /// (its box, centroid and cell would mean nothing); [`IfsError::ParameterOutOfRange`]
    /// for more than [`MAX_OCCUPANCY_GRID`] cells per side (checked before allocating:
    /// a mistyped size used to abort the process).
    pub fn of(points: &[[f64; 3]], grid: usize) -> Result<Self> {
        if grid > MAX_OCCUPANCY_GRID {
            return Err(IfsError::ParameterOutOfRange {
                name: "grid",
                value: grid.to_string(),
                reason: "at most 4096 occupancy cells per side",
            });
        }
        for (index, p) in points.iter().enumerate() {
            for (axis, &x) in p.iter().enumerate() {
                check_finite(x, || format!("point {index}, coordinate {axis}"))?;
            }
        }
        let mut min = [f64::INFINITY; 3];
        let mut max = [f64::NEG_INFINITY; 3];
        let mut sum = [0.0; 3];
        for p in points {
            for k in 0..3 {
                min[k] = min[k].min(p[k]);
                max[k] = max[k].max(p[k]);
                sum[k] += p[k];
            }
        }
        let count = points.len();
        let centroid = sum.map(|s| s / count.max(1) as f64);
        let mut occupancy = vec![vec![false; grid]; grid];
        if grid > 0 {
            let cell = |v: f64, lo: f64, hi: f64| -> usize {
                if hi > lo {
                    (((v - lo) / (hi - lo)) * grid as f64).floor().clamp(0.0, (grid - 1) as f64) as usize
                } else {
                    0
                }
            };
            for p in points {
                let (cx, cy) = (cell(p[0], min[0], max[0]), cell(p[1], min[1], max[1]));
                occupancy[grid - 1 - cy][cx] = true;
            }
        }
        Ok(Self { count, min, max, centroid, occupancy })
    }

    /// Number of occupied cells.
    pub fn occupied_cells(&self) -> usize {
        self.occupancy.iter().flatten().filter(|&&b| b).count()
    }

    /// A text summary: counts, box and centroid (9 decimals), then the occupancy rows as
    /// `#`/`.` strings.
    ///
    /// ```
    /// let stats = ifs_nonlinear::PointStats::of(&[[0.0, 0.0, 0.0], [1.0, 1.0, 0.0]], 2)?;
    /// let text = stats.to_text();
    /// assert!(text.starts_with("points 2\nmin 0.000000000 0.000000000 0.000000000\n"));
    /// assert!(text.ends_with("occupied 2\n.#\n#.\n")); // top row first: (1, 1) is top right
    /// # Ok::<(), ifs_nonlinear::IfsError>(())
    /// ```
    pub fn to_text(&self) -> String {
        let f = |v: [f64; 3]| format!("{:.9} {:.9} {:.9}", v[0], v[1], v[2]);
        let mut s = format!(
            "points {}\nmin {}\nmax {}\ncentroid {}\noccupied {}\n",
            self.count,
            f(self.min),
            f(self.max),
            f(self.centroid),
            self.occupied_cells()
        );
        for row in &self.occupancy {
            s.extend(row.iter().map(|&b| if b { '#' } else { '.' }));
            s.push('\n');
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ifs::{AffineIfs, AffineMap};

    fn sierpinski() -> AffineIfs {
        AffineIfs::from_rule(&crate::matrices::sierpinski(), &[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).unwrap()
    }

    /// Non-finite points and oversized occupancy maps are errors: a NaN point was counted
    /// in cell 0 and left the box alone, a mistyped grid aborted the process allocating.
    #[test]
    fn point_statistics_check_their_input() {
        let points = [[0.0, 0.0, 0.0], [1.0, 2.0, 0.5]];
        let stats = PointStats::of(&points, MAX_OCCUPANCY_GRID).unwrap();
        assert_eq!((stats.count, stats.max, stats.occupied_cells()), (2, [1.0, 2.0, 0.5], 2));
        for bad in [f64::NAN, f64::INFINITY] {
            let points = [[0.0, 0.0, 0.0], [1.0, 2.0, 0.5], [0.5, bad, 0.0]];
            let error = PointStats::of(&points, 4).unwrap_err();
            assert!(matches!(&error, IfsError::NotFinite { what, .. } if what == "point 2, coordinate 1"), "{error}");
        }
        for grid in [MAX_OCCUPANCY_GRID + 1, usize::MAX] {
            assert!(matches!(PointStats::of(&points, grid), Err(IfsError::ParameterOutOfRange { name: "grid", .. })));
        }
    }

    /// A point cloud draws the same at any power-of-two scale: an absolute floor of 1e-9
    /// on the view's extent drew the Sierpinski triangle at 2^-40 (extent 1e-12) as one
    /// dot. One point, or points all at the origin, still get a view.
    #[test]
    fn the_picture_does_not_depend_on_the_scale() {
        let points = deterministic_points(&sierpinski(), None, 6, 1 << 12).unwrap();
        let draw = |points: &[[f64; 3]]| render_points(points, 64, 48, Projection::Xy, ToneMap::Log).unwrap();
        let unit = draw(&points);
        for exponent in [-40, -600, 600] {
            let factor = 2f64.powi(exponent);
            let scaled: Vec<[f64; 3]> = points.iter().map(|p| p.map(|x| x * factor)).collect();
            assert!(draw(&scaled) == unit, "2^{exponent}");
        }
        for degenerate in [[[0.0; 3]; 3], [[1e-300, -2e-300, 0.0]; 3], [[3.0, 4.0, 0.0]; 3]] {
            assert_eq!(draw(&degenerate).rgba.len(), 64 * 48 * 4);
        }
    }

    #[test]
    fn deterministic_order_is_first_applied_major() {
        // Two 1D-like maps on the x axis: f0(x) = x/2, f1(x) = x/2 + 1/2; start at 1.
        let ifs = AffineIfs::new(
            2,
            vec![AffineMap::planar(0.5, 0.0, 0.0, 0.5, 0.0, 0.0), AffineMap::planar(0.5, 0.0, 0.0, 0.5, 0.5, 0.0)],
        )
        .unwrap();
        let points = deterministic_points(&ifs, Some(&[1.0, 0.0]), 2, 100).unwrap();
        // Words (v1 v2): 00 → f0(f0(1)) = 1/4; 01 → f1(f0(1)) = 3/4; 10 → f0(f1(1)) = 1/2; 11 → 1.
        let xs: Vec<f64> = points.iter().map(|p| p[0]).collect();
        assert_eq!(xs, vec![0.25, 0.75, 0.5, 1.0]);
    }

    #[test]
    fn deterministic_results_do_not_depend_on_the_thread_count() {
        let ifs = sierpinski();
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let three = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
        let a = one.install(|| deterministic_points(&ifs, None, 7, 1 << 20).unwrap());
        let b = three.install(|| deterministic_points(&ifs, None, 7, 1 << 20).unwrap());
        assert_eq!(a, b);
        let game = ChaosGame { points: 3 * CHAOS_CHUNK + 17, seed: 11, ..ChaosGame::default() };
        let c = one.install(|| chaos_points(&ifs, &game).unwrap());
        let d = three.install(|| chaos_points(&ifs, &game).unwrap());
        assert_eq!(c, d);
        let canvas = Canvas::new(40, 30, View::new([0.0, 0.0], [1.0, 1.0]).unwrap()).unwrap();
        let e = one.install(|| chaos_density(&ifs, &game, &canvas).unwrap());
        let f = three.install(|| chaos_density(&ifs, &game, &canvas).unwrap());
        assert_eq!(e, f);
        assert_eq!(e, Density::from_points(&c, &canvas).unwrap());
    }

    #[test]
    fn budget_and_parameters_are_checked() {
        let ifs = sierpinski();
        assert!(matches!(deterministic_points(&ifs, None, 20, 1000), Err(IfsError::BudgetExceeded { .. })));
        assert!(matches!(deterministic_points(&ifs, Some(&[1.0]), 1, 1000), Err(IfsError::ParameterOutOfRange { .. })));
        let zero = ChaosGame { points: 0, ..ChaosGame::default() };
        assert!(chaos_points(&ifs, &zero).is_err());
        let bad =
            ChaosGame { points: 5, probabilities: Probabilities::Custom(vec![1.0, -1.0, 1.0]), ..ChaosGame::default() };
        assert!(chaos_points(&ifs, &bad).is_err());
        // A list longer than the address space: an error before any iteration, not an
        // abort (a count the allocator refuses gives the same error).
        for points in [usize::MAX, isize::MAX as usize / 24 + 1] {
            let huge = ChaosGame { points, ..ChaosGame::default() };
            let expected = IfsError::TooManyPoints { points, bytes: points as u128 * 24 };
            assert_eq!(chaos_points(&ifs, &huge), Err(expected));
        }
        assert!(Canvas::new(0, 10, View::new([0.0, 0.0], [1.0, 1.0]).unwrap()).is_err());
        assert!(View::new([0.0, 0.0], [0.0, 1.0]).is_err());
    }

    #[test]
    fn huge_budgets_levels_burn_in_and_weights_are_errors() {
        let ifs = sierpinski();
        // Within a usize::MAX budget but beyond memory: used to abort allocating.
        let needed = 3 * 3usize.pow(30);
        assert_eq!(
            deterministic_points(&ifs, None, 30, usize::MAX),
            Err(IfsError::TooManyPoints { points: needed, bytes: needed as u128 * 24 })
        );
        // One map never exceeds the budget: u32::MAX levels used to hang.
        let single = AffineIfs::new(2, vec![AffineMap::planar(0.5, 0.0, 0.0, 0.5, 0.0, 0.0)]).unwrap();
        assert!(matches!(
            deterministic_points(&single, Some(&[1.0, 1.0]), u32::MAX, 10),
            Err(IfsError::ParameterOutOfRange { name: "levels", .. })
        ));
        let converged = deterministic_points(&single, Some(&[1.0, 1.0]), MAX_LEVELS, 10).unwrap();
        assert_eq!(converged, vec![[0.0; 3]]);
        // Levels beyond the budget still say so first.
        assert!(matches!(deterministic_points(&ifs, None, u32::MAX, 1000), Err(IfsError::BudgetExceeded { .. })));
        // A burn-in of u32::MAX per chunk used to hang.
        let game = ChaosGame { points: 5, burn_in: u32::MAX, ..ChaosGame::default() };
        assert!(matches!(chaos_points(&ifs, &game), Err(IfsError::ParameterOutOfRange { name: "burn_in", .. })));
        let game = ChaosGame { points: 5, burn_in: MAX_BURN_IN, ..ChaosGame::default() };
        assert_eq!(chaos_points(&ifs, &game).unwrap().len(), 5);
        // Finite weights whose sum is infinite used to pass and normalize to NaN.
        let game = ChaosGame { points: 5, probabilities: Probabilities::Custom(vec![f64::MAX; 3]), ..game };
        assert!(matches!(chaos_points(&ifs, &game), Err(IfsError::ParameterOutOfRange { name: "probabilities", .. })));
    }

    /// Two maps scaling by 10: not contractive. The chaos game used to return `Ok` with
    /// 867 of 1000 points infinite or NaN (and `chaos_density` an empty image); a single
    /// expanding map iterated 400 levels gave `Ok([NaN, NaN])`.
    #[test]
    fn diverging_iterations_are_errors_not_infinite_points() {
        let expanding = AffineIfs::new(
            2,
            vec![AffineMap::planar(10.0, 0.0, 0.0, 10.0, 1.0, 0.0), AffineMap::planar(10.0, 0.0, 0.0, 10.0, 0.0, 1.0)],
        )
        .unwrap();
        let game = ChaosGame { points: 1000, seed: 3, ..ChaosGame::default() };
        let err = chaos_points(&expanding, &game).unwrap_err();
        let IfsError::Diverged { index, iteration, .. } = err.clone() else { panic!("{err:?}") };
        // The error names the first non-finite point; burn-in counts in the iterations.
        assert!(index < 1000 && iteration == u64::from(game.burn_in) + index as u64 + 1, "{err}");
        assert!(err.to_string().contains("not contractive"), "{err}");
        // The same first point whatever the thread count, and for the density too.
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        assert_eq!(one.install(|| chaos_points(&expanding, &game)), Err(err.clone()));
        let canvas = Canvas::new(8, 8, View::new([0.0, 0.0], [1.0, 1.0]).unwrap()).unwrap();
        assert_eq!(chaos_density(&expanding, &game, &canvas), Err(err));

        let single = AffineIfs::new(2, vec![AffineMap::planar(10.0, 0.0, 0.0, 10.0, 1.0, 0.0)]).unwrap();
        assert!(matches!(
            deterministic_points(&single, Some(&[1.0, 1.0]), 400, 10),
            Err(IfsError::Diverged { index: 0, iteration: 400, .. })
        ));
        // Many levels that stay finite are still fine.
        assert!(deterministic_points(&single, Some(&[1.0, 1.0]), 300, 10).unwrap()[0][0].is_finite());
    }

    #[test]
    fn finiteness_test_of_points_agrees_with_is_finite() {
        for v in [0.0, -0.0, 1.0, f64::MAX, f64::MIN_POSITIVE, 5e-324, f64::INFINITY, f64::NEG_INFINITY, f64::NAN] {
            for position in 0..3 {
                let mut p = [1.0; 3];
                p[position] = v;
                assert_eq!(is_finite_point(&p), v.is_finite(), "{p:?}");
            }
        }
    }

    /// A NaN start state used to come out as NaN points (`Ok`).
    #[test]
    fn non_finite_start_states_are_named() {
        let ifs = sierpinski();
        let err = deterministic_points(&ifs, Some(&[0.5, f64::NAN]), 2, 100).unwrap_err();
        assert!(
            matches!(&err, IfsError::NotFinite { what, value } if what == "start state 0, entry 1" && value.is_nan()),
            "{err:?}"
        );
        let err = deterministic_points(&ifs, Some(&[0.0, 0.0, f64::INFINITY, 0.0]), 1, 100).unwrap_err();
        assert_eq!(err, IfsError::NotFinite { what: "start state 1, entry 0".into(), value: f64::INFINITY });
    }

    /// The fields of `Canvas` are public: a hand-built `u32::MAX × u32::MAX` canvas made
    /// `Density::from_points` abort allocating; now it is the size error of `Canvas::new`.
    #[test]
    fn hand_built_canvases_are_checked_before_allocating() {
        let good = Canvas::new(4, 4, View::new([0.0, 0.0], [1.0, 1.0]).unwrap()).unwrap();
        let point = [[0.5, 0.5, 0.0]];
        for canvas in [
            Canvas { width: u32::MAX, height: u32::MAX, ..good },
            Canvas { width: 0, ..good },
            Canvas { height: MAX_IMAGE_SIDE + 1, ..good },
        ] {
            assert!(matches!(Density::from_points(&point, &canvas), Err(IfsError::Render(_))), "{canvas:?}");
            let game = ChaosGame { points: 10, ..ChaosGame::default() };
            assert!(matches!(chaos_density(&sierpinski(), &game, &canvas), Err(IfsError::Render(_))));
        }
        let empty_view = Canvas { view: View { min: [0.0, 0.0], max: [0.0, f64::NAN] }, ..good };
        assert!(matches!(Density::from_points(&point, &empty_view), Err(IfsError::Render(_))));
        let nan_angle = good.with_projection(Projection::Orbit { azimuth: f64::NAN, elevation: 0.0 });
        assert!(matches!(Density::from_points(&point, &nan_angle), Err(IfsError::NotFinite { .. })));
        assert_eq!(Density::from_points(&point, &good).unwrap().total_points(), 1.0);
    }

    /// NaN points used to be dropped from the image without a word.
    #[test]
    fn non_finite_points_are_named_when_rendering() {
        let canvas = Canvas::new(4, 4, View::new([0.0, 0.0], [1.0, 1.0]).unwrap()).unwrap();
        let points = [[0.5, 0.5, 0.0], [0.1, 0.2, f64::NAN]];
        let names_point_1 = |result: Result<_>| matches!(result, Err(IfsError::NotFinite { what, value }) if what == "point 1, coordinate 2" && value.is_nan());
        assert!(names_point_1(Density::from_points(&points, &canvas).map(|_| ())));
        assert!(names_point_1(render_points(&points, 4, 4, Projection::Xy, ToneMap::Log).map(|_| ())));
        let orbit = Projection::Orbit { azimuth: 0.0, elevation: f64::INFINITY };
        assert!(matches!(render_points(&points[..1], 4, 4, orbit, ToneMap::Log), Err(IfsError::NotFinite { .. })));
    }

    #[test]
    fn probabilities_follow_determinants_with_a_floor() {
        let fern = AffineIfs::new(
            2,
            vec![
                AffineMap::planar(0.0, 0.0, 0.0, 0.16, 0.0, 0.0),
                AffineMap::planar(0.85, 0.04, -0.04, 0.85, 0.0, 1.6),
            ],
        )
        .unwrap();
        let t = thresholds(&fern, &Probabilities::Determinant).unwrap();
        let dets = [0.01 * 0.7241, 0.7241];
        let expected = dets[0] / (dets[0] + dets[1]);
        assert!((t[0] as f64 / 4_294_967_296.0 - expected).abs() < 1e-9);
        assert_eq!(t[1], 1 << 32);
        assert_eq!(choose(&t, 0), 0);
        assert_eq!(choose(&t, u32::MAX), 1);
    }

    #[test]
    fn splat_weights_sum_to_one_point() {
        let canvas = Canvas::new(10, 10, View::new([0.0, 0.0], [1.0, 1.0]).unwrap()).unwrap();
        let points = [[0.33, 0.71, 0.0], [0.5, 0.5, 0.0], [0.999, 0.001, 0.0]];
        let density = Density::from_points(&points, &canvas).unwrap();
        // The last point's bilinear footprint partly falls outside the image.
        assert!(density.total_points() <= 3.0 && density.total_points() > 2.0);
        let inside = Density::from_points(&points[..2], &canvas).unwrap();
        assert_eq!(inside.total_points(), 2.0);
        let png = inside.to_image(ToneMap::Log, [0, 0, 0, 255], [255; 4]).encode_png().unwrap();
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    }
}
