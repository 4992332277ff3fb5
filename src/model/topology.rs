//! Facts about the tree's shape that the dynamics algorithms use to pick their
//! fastest path, computed once when a model is built.

/// Which forward-dynamics method [`crate::dynamics::forward_dynamics`] uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FdMethod {
    /// The articulated-body algorithm, O(n).
    Aba,
    /// CRBA for H, C by RNEA, then the tree-sparse LTDL factorisation, O(n·d²).
    CrbaSparse,
    /// CRBA, `Gᵀ H G` for mimic joints, then a dense Cholesky (mimic coupling fills H).
    CrbaDense,
}

/// Tree-shape summary of a model's velocity coordinates. `depth(k)` is the number
/// of coordinates on k's path to the root, k included (k, λ(k), λ(λ(k)), …).
#[derive(Clone, Debug, PartialEq)]
pub struct Topology {
    /// The largest `depth(k)` (d in the O(n·d) / O(n·d²) costs).
    pub max_depth: usize,
    /// `Σₖ depth(k)`: the non-zeros of one triangle of H and the CRBA's force transports.
    pub sum_depth: usize,
    /// `Σₖ depth(k)²`: about twice the multiply-adds of the LTDL factorisation.
    pub sum_depth2: usize,
    /// Whether every entry of H is structurally non-zero (a chain): the CRBA then
    /// writes every entry and needs no zeroing.
    pub h_dense: bool,
    /// The forward-dynamics method, by [`Topology::choose`].
    pub fd_method: FdMethod,
    /// Whether the CRBA (without mimic joints) runs in local body frames
    /// (Pinocchio's `crba`) rather than the world frame: local wherever the tree
    /// branches or the chain is short (< 16 coordinates); the world frame's
    /// contiguous column sweep wins on longer chains. Callgrind instructions per
    /// call, world → local (joint kinds matched once per body, subtree forces
    /// carried together): ur5 5285 → 4659, solo12 14695 → 10502, talos 37589 →
    /// 30289, tree_4 12163 → 10021, chain_10 8899 → 7957, chain_20 19610 → 20708,
    /// chain_50 59909 → 84216.
    pub crba_local: bool,
    /// One past the last coordinate of k's subtree: without mimic joints the
    /// coordinates of a subtree are contiguous, `k..dof_subtree_end[k]`.
    pub dof_subtree_end: Vec<usize>,
    /// With mimic joints: whether the reduced `Gᵀ H G` keeps the tree pattern of
    /// `dof_parent` (every pair of bodies on one path to the root moves
    /// coordinates on one path of `dof_parent`, [`Topology::mimic_tree_sparse`]),
    /// so that the tree-sparse LTDL factorisation applies to it exactly (TALOS's
    /// grippers: the followers hang beside their leader). Set by the importers.
    pub mimic_tree: bool,
}

impl Default for Topology {
    fn default() -> Self {
        Self {
            max_depth: 0,
            sum_depth: 0,
            sum_depth2: 0,
            h_dense: true,
            fd_method: FdMethod::Aba,
            crba_local: false,
            dof_subtree_end: Vec::new(),
            mimic_tree: false,
        }
    }
}

impl Topology {
    /// From the parent array of the velocity coordinates (`usize::MAX` at a root),
    /// the number of bodies and whether any joint is a mimic joint.
    pub fn new(dof_parent: &[usize], nbodies: usize, has_mimic: bool) -> Self {
        let nv = dof_parent.len();
        let mut depth = vec![0usize; nv];
        for k in 0..nv {
            let p = dof_parent[k];
            depth[k] = if p < k { depth[p] + 1 } else { 1 };
        }
        let max_depth = depth.iter().copied().max().unwrap_or(0);
        let sum_depth: usize = depth.iter().sum();
        let sum_depth2: usize = depth.iter().map(|d| d * d).sum();
        let h_dense = 2 * sum_depth == nv * nv + nv;
        let mut dof_subtree_end: Vec<usize> = (1..=nv).collect();
        for k in (0..nv).rev() {
            let p = dof_parent[k];
            if p < k {
                dof_subtree_end[p] = dof_subtree_end[p].max(dof_subtree_end[k]);
            }
        }
        let mut t = Self {
            max_depth,
            sum_depth,
            sum_depth2,
            h_dense,
            fd_method: FdMethod::Aba,
            crba_local: !h_dense || nv < 16,
            dof_subtree_end,
            mimic_tree: false,
        };
        t.fd_method = t.choose(nv, nbodies, has_mimic);
        t
    }

    /// Whether `Gᵀ H G` stays inside the tree pattern of `dof_parent`: H's
    /// entry between two coordinates is a sum over pairs of bodies, one moving
    /// each, one an ancestor of the other (docs/theory.md §"Tree-sparse LTDL"),
    /// so it is enough that for every such pair of bodies (`parent`, each
    /// body's coordinates `iv..iv + nv` from `dofs(b)`) the two coordinate
    /// ranges are equal or one lies on the other's path to the root.
    pub fn mimic_tree_sparse(
        parent: &[usize],
        dofs: impl Fn(usize) -> (usize, usize),
        dof_parent: &[usize],
    ) -> bool {
        // x ancestor-or-self of y on dof_parent
        let above = |x: usize, mut y: usize| {
            while y != usize::MAX && y >= x {
                if y == x {
                    return true;
                }
                y = dof_parent[y];
            }
            false
        };
        for j in 1..parent.len() {
            let (jv, jn) = dofs(j);
            if jn == 0 {
                continue;
            }
            let mut i = parent[j];
            while i != 0 {
                let (iv, inv) = dofs(i);
                if inv > 0 && iv != jv && !above(iv + inv - 1, jv) && !above(jv + jn - 1, iv) {
                    return false;
                }
                i = parent[i];
            }
        }
        true
    }

    /// The measured cost rule: estimated instructions per call (callgrind on
    /// `examples/profile.rs`, deterministic where wall time on a shared machine is
    /// not), with B bodies, `ABA ≈ 1546·B` and
    /// `CRBA + RNEA bias + LTDL ≈ 1217·B + 90·Σdepth + 1.94·Σdepth²` (the per-body
    /// work of the bias RNEA and of the CRBA's composite inertias, the CRBA's force
    /// transports and H entries, the factorisation's multiply-adds), each fitted by
    /// relative least squares on ur5, kinova, solo12, talos_reduced, chains of
    /// 5–50 and binary trees of depth 4–8 (benches/results.md, "fd rule"). Within
    /// 6% of every measured count; the rule picks CRBA + LTDL for small branching
    /// trees (tree_4: 20980 against ABA's 23133) and short chains (chain_5, a 2%
    /// tie), ABA elsewhere, and CRBA + dense Cholesky wherever ABA cannot go:
    /// mimic joints.
    pub fn choose(&self, _nv: usize, nbodies: usize, has_mimic: bool) -> FdMethod {
        if has_mimic {
            return FdMethod::CrbaDense;
        }
        let b = nbodies.saturating_sub(1) as f64;
        let aba = ABA_PER_BODY * b;
        let crba = CRBA_PER_BODY * b
            + CRBA_PER_DEPTH * self.sum_depth as f64
            + LTDL_PER_DEPTH2 * self.sum_depth2 as f64;
        if crba < aba {
            FdMethod::CrbaSparse
        } else {
            FdMethod::Aba
        }
    }
}

/// Cost-model coefficients (instructions), fitted as in `Topology::choose`.
const ABA_PER_BODY: f64 = 1546.0;
const CRBA_PER_BODY: f64 = 1217.0;
const CRBA_PER_DEPTH: f64 = 90.0;
const LTDL_PER_DEPTH2: f64 = 1.94;
