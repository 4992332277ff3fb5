//! The worker pools of `rollout(..., threads=n)` and `linearize(..., threads=n)`:
//! one pool a thread count, started at its first use and kept for the process,
//! so that a call does not start (and stop) its threads anew and its workers
//! keep their warm allocator caches between calls. A forked child (which
//! inherits no threads) starts its own.

use std::sync::{Arc, Mutex, OnceLock};

/// Pools by thread count, with the process that started them.
type Pools = Vec<(usize, u32, Arc<rayon::ThreadPool>)>;

/// The pool of `n` threads (started once a process; later calls share it).
pub fn pool(n: usize) -> Result<Arc<rayon::ThreadPool>, String> {
    static POOLS: OnceLock<Mutex<Pools>> = OnceLock::new();
    let pools = POOLS.get_or_init(|| Mutex::new(Vec::new()));
    // a poisoned lock only means another call panicked while holding it: the
    // list itself is whole (each change is one statement)
    let mut pools = pools.lock().unwrap_or_else(|e| e.into_inner());
    let pid = std::process::id();
    if let Some((_, _, p)) = pools.iter().find(|(k, at, _)| *k == n && *at == pid) {
        return Ok(p.clone());
    }
    // a parent's pools (after a fork) have no threads here: forgotten, not joined
    pools.retain(|(_, at, _)| *at == pid);
    let p = Arc::new(
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map_err(|e| e.to_string())?,
    );
    pools.push((n, pid, p.clone()));
    Ok(p)
}
