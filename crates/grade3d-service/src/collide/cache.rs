//! Per-body cache of what collision needs: the depth maps (rendered once per
//! body, seed 000 §5.4) and the exact inside test's hierarchy.
//!
//! Keys are content addresses: BLAKE3 of the body's positions and
//! triangles (little-endian `f64` / `u32`) and of the [`RenderOptions`], so
//! the same scan posted twice, or the same size-chart mannequin graded with
//! another template, reuses its maps. Least-recently-used eviction at
//! [`ObstacleCacheOptions::capacity`] entries (`moka`). Concurrent misses of
//! one body build it once. Hits and misses are counted for the service's
//! metrics. No failure modes of its own: the builder's error is
//! passed through and nothing is cached.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use super::render::RenderOptions;
use crate::geom::mesh::TriMesh;

/// Content address of one body under one set of render options.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct BodyKey(pub [u8; 32]);

impl BodyKey {
    /// BLAKE3 of the mesh (positions, triangles) and the render options.
    pub fn of(mesh: &TriMesh, opts: &RenderOptions) -> Self {
        let mut h = blake3::Hasher::new();
        h.update(b"grade3d body v1");
        h.update(&(mesh.positions().len() as u64).to_le_bytes());
        for p in mesh.positions() {
            for c in p.to_array() {
                h.update(&c.to_le_bytes());
            }
        }
        h.update(&(mesh.triangles().len() as u64).to_le_bytes());
        for t in mesh.triangles() {
            for v in t {
                h.update(&v.0.to_le_bytes());
            }
        }
        h.update(&opts.resolution.to_le_bytes());
        h.update(format!("{:?}", opts.views).as_bytes());
        h.update(&opts.padding_mm.to_le_bytes());
        Self(*h.finalize().as_bytes())
    }
}

pub use crate::collide::Obstacle;

/// Knobs of the cache.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct ObstacleCacheOptions {
    /// Bodies kept (count); about 35 MB each at 1024² (two views, front and
    /// back, as rendered: 32 MB of maps, and the winding tree). Default 16.
    pub capacity: usize,
}

impl Default for ObstacleCacheOptions {
    fn default() -> Self {
        Self { capacity: 16 }
    }
}

/// LRU cache of [`Obstacle`]s keyed by [`BodyKey`]; shareable across
/// threads. A `moka` cache (issue #16: it replaced a hand-kept deque):
/// least recently used out past [`ObstacleCacheOptions::capacity`], and
/// concurrent misses of one body build it once (the others wait for it).
#[derive(Debug)]
pub struct ObstacleCache {
    entries: moka::sync::Cache<BodyKey, Arc<Obstacle>>,
    hits: AtomicU64,
    misses: AtomicU64,
}

impl ObstacleCache {
    /// An empty cache.
    pub fn new(opts: ObstacleCacheOptions) -> Self {
        let entries = moka::sync::Cache::builder()
            .max_capacity(opts.capacity as u64)
            .eviction_policy(moka::policy::EvictionPolicy::lru())
            .build();
        Self { entries, hits: AtomicU64::new(0), misses: AtomicU64::new(0) }
    }

    /// The cached obstacle of `key`, or `build()`'s, inserted.
    ///
    /// # Errors
    /// `build`'s error; nothing is cached then.
    pub fn get_or_build<E: Clone + Send + Sync + 'static>(
        &self,
        key: BodyKey,
        build: impl FnOnce() -> Result<Obstacle, E>,
    ) -> Result<Arc<Obstacle>, E> {
        if self.entries.policy().max_capacity() == Some(0) {
            self.misses.fetch_add(1, Ordering::Relaxed);
            return build().map(Arc::new);
        }
        // one lookup: the entry is fresh when this call built it (a concurrent miss of the
        // same body waits for that build and is served from it)
        let entry = self
            .entries
            .entry(key)
            .or_try_insert_with(|| build().map(Arc::new))
            .map_err(|e| Arc::try_unwrap(e).unwrap_or_else(|shared| (*shared).clone()))?;
        if entry.is_fresh() {
            self.misses.fetch_add(1, Ordering::Relaxed);
            // evict now, not at the next housekeeping: the capacity bounds memory
            self.entries.run_pending_tasks();
        } else {
            self.hits.fetch_add(1, Ordering::Relaxed);
        }
        Ok(entry.into_value())
    }

    /// Lookups served from the cache.
    pub fn hits(&self) -> u64 {
        self.hits.load(Ordering::Relaxed)
    }

    /// Lookups that built.
    pub fn misses(&self) -> u64 {
        self.misses.load(Ordering::Relaxed)
    }

    /// Bodies held now.
    pub fn len(&self) -> usize {
        self.entries.run_pending_tasks();
        self.entries.entry_count() as usize
    }

    /// Whether no body is held.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::mesh::TriMesh;
    use crate::geom::winding::{WindingOptions, WindingTree};

    fn obstacle(mesh: &TriMesh) -> Obstacle {
        Obstacle { maps: Vec::new(), tree: WindingTree::new(mesh, &WindingOptions::default()) }
    }

    #[test]
    fn same_body_hits_other_body_or_options_miss_and_lru_evicts() {
        let a = TriMesh::icosahedron();
        let b = TriMesh::new(a.positions().iter().map(|p| *p * 2.0).collect(), a.triangles().to_vec())
            .expect("scaled icosahedron");
        let opts = RenderOptions::default();
        let low = RenderOptions { resolution: 512, ..opts };
        assert_eq!(BodyKey::of(&a, &opts), BodyKey::of(&a.clone(), &opts));
        assert_ne!(BodyKey::of(&a, &opts), BodyKey::of(&b, &opts));
        assert_ne!(BodyKey::of(&a, &opts), BodyKey::of(&a, &low));

        let cache = ObstacleCache::new(ObstacleCacheOptions { capacity: 2 });
        let mut builds = 0;
        let mut get = |m: &TriMesh, o: &RenderOptions| {
            cache
                .get_or_build(BodyKey::of(m, o), || {
                    builds += 1;
                    Ok::<_, ()>(obstacle(m))
                })
                .expect("build")
        };
        let first = get(&a, &opts);
        get(&b, &opts);
        let again = get(&a, &opts); // hit: a is now the most recently used
        assert!(Arc::ptr_eq(&first, &again));
        get(&a, &low); // evicts the least recently used: b
        get(&a, &opts);
        get(&b, &opts); // built again
        assert_eq!(builds, 4);
        assert_eq!((cache.hits(), cache.misses()), (2, 4));
        assert_eq!(cache.len(), 2);
        let failed = cache.get_or_build(BodyKey([7; 32]), || Err::<Obstacle, _>("no adapter"));
        assert_eq!(failed.unwrap_err(), "no adapter");
        assert_eq!(cache.len(), 2, "failures are not cached");
    }
}
