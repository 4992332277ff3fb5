//! A process-wide cache of what contact makes from a mesh file (its convex
//! hull for the ground path, its parry shape for the pairs), so that building
//! a second simulation of the same model (a batch of rollouts, a `reset`, a
//! new `Simulation` from Python) reads no file and computes no hull again.
//!
//! An entry is keyed by what it is (`kind`), the resolved path, the scale and
//! the file's length and modification time: a file changed on disk is read
//! anew. Only successes are kept (a missing or bad file is reported every
//! time); what is made is a pure function of the file's bytes and the scale,
//! so a hit is bit for bit what a miss would make. At most [`MAX_ENTRIES`]
//! entries: past that the cache starts again empty.

use std::any::Any;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, MutexGuard, OnceLock};
use std::time::SystemTime;

/// The most entries kept (a scene of many different meshes starts the cache
/// over rather than growing it without bound).
const MAX_ENTRIES: usize = 512;

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
struct Key {
    kind: &'static str,
    path: PathBuf,
    scale: [u64; 3],
    len: u64,
    modified: SystemTime,
}

type Entries = HashMap<Key, Arc<dyn Any + Send + Sync>>;

fn entries() -> MutexGuard<'static, Entries> {
    static CACHE: OnceLock<Mutex<Entries>> = OnceLock::new();
    // a thread that panicked while holding the lock left a valid map (every
    // change is one insert or clear): use it
    CACHE
        .get_or_init(|| Mutex::new(HashMap::new()))
        .lock()
        .unwrap_or_else(|p| p.into_inner())
}

/// The entry `kind` of the file at `path` scaled by `scale`: the kept one
/// when the file has not changed since it was made, else `make()` (kept
/// when it succeeds). A file whose length or time cannot be read is not
/// cached.
pub(crate) fn cached<T, E>(
    kind: &'static str,
    path: &Path,
    scale: [f64; 3],
    make: impl FnOnce() -> Result<T, E>,
) -> Result<Arc<T>, E>
where
    T: Send + Sync + 'static,
{
    let key = std::fs::metadata(path).ok().and_then(|m| {
        Some(Key {
            kind,
            path: path.to_path_buf(),
            scale: scale.map(f64::to_bits),
            len: m.len(),
            modified: m.modified().ok()?,
        })
    });
    let Some(key) = key else {
        return make().map(Arc::new);
    };
    let hit = entries().get(&key).cloned();
    if let Some(t) = hit.and_then(|h| h.downcast::<T>().ok()) {
        return Ok(t);
    }
    let made = Arc::new(make()?);
    let mut all = entries();
    if all.len() >= MAX_ENTRIES {
        all.clear();
    }
    all.insert(key, made.clone());
    Ok(made)
}
