//! The sweeps' kernels over a contact's three rows (pgs.rs, subspace.rs):
//! their dots and updates along its path, each entry the same operations in
//! the same order as the scalar row-by-row loop, four lanes at a time where
//! AVX is enabled.

/// `$run` with the slices named cut to 6 or 12 entries when `$n` is that
/// length (a free body's path, two free bodies': a loop of that known trip
/// count, which LLVM unrolls whole, with no loop bookkeeping), else with the
/// slices as they are: the same operations in the same order either way.
/// `$n` must be ≤ every named slice's length.
macro_rules! at_path_len {
    ($n:expr; $($s:ident),+ => $run:expr) => {
        match $n {
            6 => {
                // SAFETY: 6 = n ≤ every slice's length (the caller's)
                $( let $s = unsafe { $s.get_unchecked(..6) }; )+
                $run
            }
            12 => {
                // SAFETY: 12 = n ≤ every slice's length (the caller's)
                $( let $s = unsafe { $s.get_unchecked(..12) }; )+
                $run
            }
            _ => $run,
        }
    };
}
pub(super) use at_path_len;

/// Where the slots of a contact's path lie in Δv': the path itself (slot t
/// at dof `p[t]`, gathered), or [`Runs`]. The kernels below read and write
/// the same entries either way, in the same order.
pub(super) trait Dofs: Copy {
    /// Slot t's dof.
    ///
    /// # Safety
    /// t is below the path's length (a gathered path is read unchecked).
    unsafe fn at(self, t: usize) -> usize;
    /// Slots t … t + w − 1 are consecutive dofs (a constant for [`Runs`]
    /// once the loop is unrolled; never for a gathered path).
    fn consecutive(self, t: usize, w: usize) -> bool;
}

impl Dofs for &[usize] {
    #[inline(always)]
    unsafe fn at(self, t: usize) -> usize {
        // SAFETY: t < the path's length (the caller's)
        unsafe { *self.get_unchecked(t) }
    }
    #[inline(always)]
    fn consecutive(self, _: usize, _: usize) -> bool {
        false
    }
}

/// `K` runs of six consecutive dofs, from their first (a free body's chain,
/// two free bodies': a pile's ground contact, its pair contact): slot t at
/// dof `self.0[t / 6] + t % 6`, read without the path.
#[derive(Clone, Copy)]
pub(super) struct Runs<const K: usize>(pub [usize; K]);

impl<const K: usize> Dofs for Runs<K> {
    #[inline(always)]
    unsafe fn at(self, t: usize) -> usize {
        self.0[t / 6] + t % 6
    }
    #[inline(always)]
    fn consecutive(self, t: usize, w: usize) -> bool {
        t % 6 + w <= 6
    }
}

/// A contact's path as the sweeps' update writes it (pgs.rs, [`axpy3_path`]):
/// one run of six dofs, two, or any other path (gathered, [`axpy3`]).
#[derive(Clone, Copy)]
pub(super) enum Path<'a> {
    One(Runs<1>),
    Two(Runs<2>),
    Any(&'a [usize]),
}

impl<'a> Path<'a> {
    /// `p`'s runs: a path is ascending (root … leaf, or two such joined,
    /// [`super::Rows::union_path`]), so six slots that span six dofs are
    /// consecutive; every dof read stays within the path's first and last.
    #[inline(always)]
    pub(super) fn of(p: &'a [usize]) -> Self {
        debug_assert!(p.windows(2).all(|w| w[0] < w[1]));
        match *p {
            [a, _, _, _, _, f] if f == a + 5 => Path::One(Runs([a])),
            [a, _, _, _, _, f, b, _, _, _, _, g] if f == a + 5 && g == b + 5 => {
                Path::Two(Runs([a, b]))
            }
            _ => Path::Any(p),
        }
    }
}

/// [`axpy3`] over a contact's [`Path`].
///
/// # Safety
/// Each of `ys` is at least the path's length (its runs are read unchecked).
#[inline(always)]
pub(super) unsafe fn axpy3_path(a: [f64; 3], ys: [&[f64]; 3], p: Path, x: &mut [f64]) {
    // SAFETY: each of ys is at least the path's length (the caller's)
    let cut = |n: usize| ys.map(|y| unsafe { y.get_unchecked(..n) });
    match p {
        Path::One(d) => path3_run::<Axpy, _>(a, cut(6), d, x, 6),
        Path::Two(d) => path3_run::<Axpy, _>(a, cut(12), d, x, 12),
        Path::Any(p) => axpy3(a, ys, p, x),
    }
}

/// yᵣ·x = Σₜ yₜ x[pₜ] from 0 in path order (`y` a row, `p` its path; the
/// scalar loop `d += y x`), an entry past x's end read as 0 (a checked
/// gather); a path of [`Runs`] read as slices of x, checked once a run.
pub(super) fn dot_checked(y: &[f64], p: &[usize], x: &[f64]) -> f64 {
    let six = |s: &[f64], a: usize| -> Option<[f64; 6]> { s.get(a..)?.get(..6)?.try_into().ok() };
    // d + Σₜ yₜ xₜ over six slots, in order
    let dot6 = |d: f64, y: [f64; 6], x: [f64; 6]| (0..6).fold(d, |d, t| d + y[t] * x[t]);
    match Path::of(p) {
        Path::One(Runs([a])) => {
            if let (Some(ys), Some(xs)) = (six(y, 0), six(x, a)) {
                return dot6(0.0, ys, xs);
            }
        }
        Path::Two(Runs([a, b])) => {
            if let (Some(y0), Some(y1), Some(x0), Some(x1)) =
                (six(y, 0), six(y, 6), six(x, a), six(x, b))
            {
                return dot6(dot6(0.0, y0, x0), y1, x1);
            }
        }
        Path::Any(_) => {}
    }
    y.iter()
        .zip(p)
        .fold(0.0, |d, (&v, &k)| d + v * x.get(k).copied().unwrap_or(0.0))
}

/// Δv' += Σᵣ λᵣ yᵣ over rows `s..e` in row order, a contact's three rows in
/// one pass over their path ([`warm3`]) when all three λ ≠ 0: the warm start
/// of an island's runs in its sweeps (pgs.rs) and of every row at once
/// ([`super::Rows::warm_velocity`], split.rs), one arithmetic for both, so the
/// two starts are the same bits on an island's dofs.
///
/// # Safety
/// The caller has checked the rows `s..e`: every path within `table`, at
/// most `st` long, its dofs < `x.len()`; `y` holds `st` entries
/// a row (the sweeps' checks, [`super::Rows::sweeps`]).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) unsafe fn warm_rows(
    lambda: &[f64],
    contact: &[bool],
    paths: &[(usize, usize)],
    table: &[usize],
    y: &[f64],
    st: usize,
    (s, e): (usize, usize),
    x: &mut [f64],
) {
    let mut r = s;
    while r < e {
        let l = lambda[r];
        let (ps, pl) = paths[r];
        // SAFETY: the caller's checks (the path in `table`, its row of y
        // within them, its dofs < x.len())
        let p = unsafe { table.get_unchecked(ps..ps + pl) };
        if contact[r] && r + 2 < e && l != 0.0 && lambda[r + 1] != 0.0 && lambda[r + 2] != 0.0 {
            // each entry ((x + λₙyₙ) + λ₁y₁) + λ₂y₂, the row-by-row order
            // SAFETY: rows r..r + 3 < e ≤ n, each st ≥ pl entries of y (the
            // caller's checks)
            let yr = |q: usize| unsafe { y.get_unchecked(q * st..q * st + pl) };
            warm3(
                [l, lambda[r + 1], lambda[r + 2]],
                [yr(r), yr(r + 1), yr(r + 2)],
                p,
                x,
            );
            r += 3;
            continue;
        }
        if l != 0.0 {
            for (t, &k) in p.iter().enumerate() {
                unsafe { *x.get_unchecked_mut(k) += l * y.get_unchecked(r * st + t) };
            }
        }
        r += 1;
    }
}

/// The warm start of a contact's three rows over its path `p`:
/// x[pₜ] = ((x[pₜ] + a₀ y₀ₜ) + a₁ y₁ₜ) + a₂ y₂ₜ (`ys`: its three rows of y,
/// each at least `p.len()` long), each entry the same sum as three row-by-row
/// updates ([`path3`]'s lanes); the indices of `p` must be < `x.len()` and
/// distinct.
#[inline(always)]
pub(super) fn warm3(a: [f64; 3], ys: [&[f64]; 3], p: &[usize], x: &mut [f64]) {
    path3::<Warm>(a, ys, p, x);
}

/// The contact's update x[pₜ] += (a₀ y₀ₜ + a₁ y₁ₜ) + a₂ y₂ₜ over a contact's
/// path `p` (its three rows of y, `ys`, each at least `p.len()` long), each
/// entry the same operations in the same order as the scalar loop
/// ([`path3`]'s lanes); the indices of `p` must be < `x.len()` (a row's path:
/// dof indices < nv) and distinct.
#[inline(always)]
pub(super) fn axpy3(a: [f64; 3], ys: [&[f64]; 3], p: &[usize], x: &mut [f64]) {
    path3::<Axpy>(a, ys, p, x);
}

/// How [`path3`] sums an entry x and a contact's three products aᵢyᵢ, the
/// same order in every width: a scalar, two SSE2 lanes, four AVX lanes.
trait Sum3 {
    fn scalar(x: f64, a: [f64; 3], y: [f64; 3]) -> f64;
    /// # Safety
    /// SSE2 (part of x86_64): none beyond the target's.
    #[cfg(target_arch = "x86_64")]
    unsafe fn sse(
        x: std::arch::x86_64::__m128d,
        a: [std::arch::x86_64::__m128d; 3],
        y: [std::arch::x86_64::__m128d; 3],
    ) -> std::arch::x86_64::__m128d;
    /// # Safety
    /// AVX enabled at compile time (the only build that calls it).
    #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
    unsafe fn avx(
        x: std::arch::x86_64::__m256d,
        a: [std::arch::x86_64::__m256d; 3],
        y: [std::arch::x86_64::__m256d; 3],
    ) -> std::arch::x86_64::__m256d;
}

/// [`warm3`]'s order: ((x + a₀y₀) + a₁y₁) + a₂y₂.
struct Warm;
/// [`axpy3`]'s order: x + ((a₀y₀ + a₁y₁) + a₂y₂).
struct Axpy;

impl Sum3 for Warm {
    #[inline(always)]
    fn scalar(x: f64, a: [f64; 3], y: [f64; 3]) -> f64 {
        ((x + a[0] * y[0]) + a[1] * y[1]) + a[2] * y[2]
    }
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn sse(
        x: std::arch::x86_64::__m128d,
        a: [std::arch::x86_64::__m128d; 3],
        y: [std::arch::x86_64::__m128d; 3],
    ) -> std::arch::x86_64::__m128d {
        use std::arch::x86_64::*;
        // SAFETY: SSE2 is part of x86_64
        unsafe {
            let v = _mm_add_pd(x, _mm_mul_pd(a[0], y[0]));
            let v = _mm_add_pd(v, _mm_mul_pd(a[1], y[1]));
            _mm_add_pd(v, _mm_mul_pd(a[2], y[2]))
        }
    }
    #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
    #[inline(always)]
    unsafe fn avx(
        x: std::arch::x86_64::__m256d,
        a: [std::arch::x86_64::__m256d; 3],
        y: [std::arch::x86_64::__m256d; 3],
    ) -> std::arch::x86_64::__m256d {
        use std::arch::x86_64::*;
        // SAFETY: avx is enabled at compile time
        unsafe {
            let v = _mm256_add_pd(x, _mm256_mul_pd(a[0], y[0]));
            let v = _mm256_add_pd(v, _mm256_mul_pd(a[1], y[1]));
            _mm256_add_pd(v, _mm256_mul_pd(a[2], y[2]))
        }
    }
}

impl Sum3 for Axpy {
    #[inline(always)]
    fn scalar(x: f64, a: [f64; 3], y: [f64; 3]) -> f64 {
        x + (a[0] * y[0] + a[1] * y[1] + a[2] * y[2])
    }
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn sse(
        x: std::arch::x86_64::__m128d,
        a: [std::arch::x86_64::__m128d; 3],
        y: [std::arch::x86_64::__m128d; 3],
    ) -> std::arch::x86_64::__m128d {
        use std::arch::x86_64::*;
        // SAFETY: SSE2 is part of x86_64
        unsafe {
            let s = _mm_add_pd(_mm_mul_pd(a[0], y[0]), _mm_mul_pd(a[1], y[1]));
            _mm_add_pd(x, _mm_add_pd(s, _mm_mul_pd(a[2], y[2])))
        }
    }
    #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
    #[inline(always)]
    unsafe fn avx(
        x: std::arch::x86_64::__m256d,
        a: [std::arch::x86_64::__m256d; 3],
        y: [std::arch::x86_64::__m256d; 3],
    ) -> std::arch::x86_64::__m256d {
        use std::arch::x86_64::*;
        // SAFETY: avx is enabled at compile time
        unsafe {
            let s = _mm256_add_pd(_mm256_mul_pd(a[0], y[0]), _mm256_mul_pd(a[1], y[1]));
            _mm256_add_pd(x, _mm256_add_pd(s, _mm256_mul_pd(a[2], y[2])))
        }
    }
}

/// x[pₜ] = S(x[pₜ], a, yₜ) over a contact's path `p` (its three rows of y,
/// `ys`, each at least `p.len()` long; [`Sum3`]: the order of the sums),
/// four path slots at a time with AVX, then two at a time in SSE2 lanes on
/// x86_64 (the whole path on SSE builds, x86-64 and x86-64-v2: callgrind's;
/// the slots past the last four with AVX, a ground contact's 6), then a
/// scalar tail; gathered and scattered (a path's dofs are distinct), each
/// lane the scalar operations in their order. The indices of `p` must be
/// < `x.len()` (a row's path: dof indices < nv).
#[inline(always)]
fn path3<S: Sum3>(a: [f64; 3], ys: [&[f64]; 3], p: &[usize], x: &mut [f64]) {
    let n = p.len().min(ys[0].len()).min(ys[1].len()).min(ys[2].len());
    // a free body's path (6 dofs) and two free bodies' (12) at their fixed
    // length, unrolled whole (`dot3::dot3_from`'s): the same lanes
    let [y0, y1, y2] = ys;
    at_path_len!(n; y0, y1, y2, p => path3_run::<S, _>(a, [y0, y1, y2], p, x, n))
}

/// Slots t, t + 1's entries of x (at `xp`) in two lanes: one load where
/// their dofs are consecutive, else gathered.
///
/// # Safety
/// Both dofs < x's length.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn x2<D: Dofs>(xp: *const f64, p: D, t: usize) -> std::arch::x86_64::__m128d {
    use std::arch::x86_64::*;
    // SAFETY: the caller's
    unsafe {
        if p.consecutive(t, 2) {
            _mm_loadu_pd(xp.add(p.at(t)))
        } else {
            _mm_loadh_pd(_mm_load_sd(xp.add(p.at(t))), xp.add(p.at(t + 1)))
        }
    }
}

/// [`x2`]'s store of `v` back (the same entries).
///
/// # Safety
/// Both dofs < x's length.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn put2<D: Dofs>(xp: *mut f64, p: D, t: usize, v: std::arch::x86_64::__m128d) {
    use std::arch::x86_64::*;
    // SAFETY: the caller's
    unsafe {
        if p.consecutive(t, 2) {
            _mm_storeu_pd(xp.add(p.at(t)), v);
        } else {
            _mm_storel_pd(xp.add(p.at(t)), v);
            _mm_storeh_pd(xp.add(p.at(t + 1)), v);
        }
    }
}

/// [`path3`]'s loops over the first `n` slots (n ≤ every slice's length).
#[inline(always)]
fn path3_run<S: Sum3, D: Dofs>(a: [f64; 3], ys: [&[f64]; 3], p: D, x: &mut [f64], n: usize) {
    // SAFETY: t < n ≤ the path's length (the caller's)
    let at = |t: usize| unsafe { p.at(t) };
    debug_assert!((0..n).all(|t| at(t) < x.len()));
    debug_assert!((0..n).all(|t| (0..t).all(|i| at(i) != at(t))));
    debug_assert!(n <= ys[0].len().min(ys[1].len()).min(ys[2].len()));
    let [y0, y1, y2] = ys;
    #[allow(unused_mut)]
    let mut t = 0;
    #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
    {
        use std::arch::x86_64::*;
        // SAFETY: avx is enabled at compile time; t + 3 < n ≤ every slice's
        // length; every k < x.len() (the sweeps' check of the paths), and the
        // four k of a group are distinct (a path lists a dof once)
        unsafe {
            let aa = [
                _mm256_set1_pd(a[0]),
                _mm256_set1_pd(a[1]),
                _mm256_set1_pd(a[2]),
            ];
            let xp = x.as_mut_ptr();
            while t + 4 <= n {
                let yy = [
                    _mm256_loadu_pd(y0.as_ptr().add(t)),
                    _mm256_loadu_pd(y1.as_ptr().add(t)),
                    _mm256_loadu_pd(y2.as_ptr().add(t)),
                ];
                let k = [p.at(t), p.at(t + 1), p.at(t + 2), p.at(t + 3)];
                if p.consecutive(t, 4) {
                    let v = S::avx(_mm256_loadu_pd(xp.add(k[0])), aa, yy);
                    _mm256_storeu_pd(xp.add(k[0]), v);
                    t += 4;
                    continue;
                }
                let lo = x2(xp, p, t);
                let hi = x2(xp, p, t + 2);
                let v = S::avx(_mm256_set_m128d(hi, lo), aa, yy);
                let (vlo, vhi) = (_mm256_castpd256_pd128(v), _mm256_extractf128_pd::<1>(v));
                put2(xp, p, t, vlo);
                put2(xp, p, t + 2, vhi);
                t += 4;
            }
        }
    }
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::*;
        // SAFETY: SSE2 is part of x86_64; t + 1 < n ≤ every slice's length;
        // every k < x.len() (the sweeps' check of the paths), and the two k
        // of a pair are distinct (a path lists a dof once)
        unsafe {
            let aa = [_mm_set1_pd(a[0]), _mm_set1_pd(a[1]), _mm_set1_pd(a[2])];
            let xp = x.as_mut_ptr();
            while t + 2 <= n {
                let yy = [
                    _mm_loadu_pd(y0.as_ptr().add(t)),
                    _mm_loadu_pd(y1.as_ptr().add(t)),
                    _mm_loadu_pd(y2.as_ptr().add(t)),
                ];
                let v = S::sse(x2(xp, p, t), aa, yy);
                put2(xp, p, t, v);
                t += 2;
            }
        }
    }
    while t < n {
        // SAFETY: t < n ≤ every slice's length; p[t] < x.len() (as above)
        unsafe {
            let xk = x.get_unchecked_mut(p.at(t));
            let yt = [
                *y0.get_unchecked(t),
                *y1.get_unchecked(t),
                *y2.get_unchecked(t),
            ];
            *xk = S::scalar(*xk, a, yt);
        }
        t += 1;
    }
}

/// Below how much of its slack a pinned row is taken to be held, relative
/// to 1 + |u|: room for the rounding of u and of Δv' (about 1e-15 of them).
const PIN_MARGIN: f64 = 1e-9;

/// Up to which `drift` a row held at a bound by its velocity stays held: a
/// row at its bound with `slack` = how far its velocity `u` lies on the
/// holding side of its target (uᵣ − bᵣ for an inactive normal or limit at
/// λ = 0; bᵣ − uᵣ at a joint friction's +limit, uᵣ − bᵣ at its −limit) keeps
/// its impulse, and moves nothing, while u stays on that side. Every update
/// since adds |Δλ_q| ‖y_q‖ = |Δλ_q| √W_qq to `drift`, a bound on ‖Δv'‖ by the
/// triangle inequality, and Cauchy–Schwarz bounds |Δuᵣ| = |yᵣ·Δv'| by
/// √Wᵣᵣ ‖Δv'‖: so while `drift` − (its value now) < slack/√Wᵣᵣ (less a
/// margin for rounding) the row's update is provably the one that leaves it
/// pinned, and the sweeps skip it (the same λ and Δv' bit for bit).
/// `NEG_INFINITY` (never skipped) when the slack is not positive.
#[inline(always)]
pub(super) fn pinned_until(drift: f64, slack: f64, u: f64, w: f64) -> f64 {
    let s = slack - PIN_MARGIN * (1.0 + u.abs());
    if s > 0.0 && w > 0.0 {
        drift + s / w.sqrt()
    } else {
        f64::NEG_INFINITY
    }
}

/// A tangent pair's update when its Gauss–Seidel step leaves the cone (the
/// point slides): one isotropic step, λₜ − uₜ/w̄ with `wbar` = w̄ at least the
/// largest eigenvalue of the pair's 2 × 2 Delassus block, projected onto the disc
/// of radius `lim`. A fixed point of it is the exact Coulomb law: λₜ = s (λₜ − uₜ/w̄)
/// with s < 1 makes λₜ anti-parallel to the slip uₜ, ‖λₜ‖ = μλₙ (maximal
/// dissipation; the per-row diagonal step would leave λₜ anti-parallel to
/// D⁻¹uₜ instead, off by the block's anisotropy: docs/theory.md §"Constraint
/// solve"). Inside the cone (sticking) the diagonal step is kept.
#[inline]
pub(super) fn slide_onto_cone(
    o1: f64,
    o2: f64,
    u1: f64,
    u2: f64,
    wbar: f64,
    lim: f64,
) -> (f64, f64) {
    if !(wbar > 1e-14) {
        return (0.0, 0.0);
    }
    let (t1, t2) = (o1 - u1 / wbar, o2 - u2 / wbar);
    let m = (t1 * t1 + t2 * t2).sqrt();
    if m > lim {
        let s = if m > 0.0 { lim / m } else { 0.0 };
        (t1 * s, t2 * s)
    } else {
        (t1, t2)
    }
}
