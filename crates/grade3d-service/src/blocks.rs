//! Each template's *block*: its dart plan on the body it was designed on
//! (issue #15), which a scan's pattern starts from
//! ([`grade3d_core::pattern::garment::DartSource::Block`]).
//!
//! Made-to-measure as a pattern maker drafts it: the customer's pattern is
//! the style's block altered to the customer, with its darts where the
//! block has them, each opening by what this body needs; only where the
//! block's darts do not hold on a body (a dart that does not open, a piece
//! that folds, a piece the block gives no dart that strains past the dart
//! search's target) is the pattern decided on the body itself. The darts
//! of a style are then the same on every customer, as they are on every
//! size of a chart run — and a scan's pattern is not held up by the dart
//! search (two rounds of 24 trial flattenings per piece on a trouser
//! scan: about 80 of its 125 ms of pattern).
//!
//! The block is the template graded on the reference body it is authored
//! on ([`grade3d_core::template::library::reference_body`]) with the
//! run's grading options, its darts decided there
//! ([`grade3d_core::pattern::garment::DartSource::Decide`]). It is a
//! function of the template and those options alone, so it is made once
//! per process and template and kept: the service makes the live
//! templates' blocks as it starts (after the renderer), and a template
//! first graded before its block is ready waits for the one build.
//!
//! Keys are content addresses: BLAKE3 of the template's JSON document.
//! Failure modes: none of its own. A template that cannot be graded on the
//! reference body has no block (its scans decide their darts, as before);
//! the builder's failure is logged, not cached, and not a request's error.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use crate::pattern::garment::DartPlan;
use crate::template::format::Template;

/// Content address of one template document.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TemplateKey(pub [u8; 32]);

impl TemplateKey {
    /// BLAKE3 of the template's JSON document.
    pub fn of(t: &Template) -> Self {
        let mut h = blake3::Hasher::new();
        h.update(b"grade3d template v1");
        h.update(t.to_json().as_bytes());
        Self(*h.finalize().as_bytes())
    }
}

/// Knobs of the block cache.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct BlockCacheOptions {
    /// Templates whose block is kept (count; a plan is a few kilobytes).
    /// Default 256.
    pub capacity: usize,
}

impl Default for BlockCacheOptions {
    fn default() -> Self {
        Self { capacity: 256 }
    }
}

/// The blocks made so far, keyed by [`TemplateKey`]; shareable across
/// threads (`moka`: least recently used out past the capacity, and
/// concurrent misses of one template build it once).
#[derive(Debug)]
pub struct BlockCache {
    entries: moka::sync::Cache<TemplateKey, Arc<DartPlan>>,
    misses: AtomicU64,
}

impl Default for BlockCache {
    fn default() -> Self {
        Self::new(BlockCacheOptions::default())
    }
}

impl BlockCache {
    /// An empty cache.
    pub fn new(opts: BlockCacheOptions) -> Self {
        let entries = moka::sync::Cache::builder().max_capacity(opts.capacity as u64).build();
        Self { entries, misses: AtomicU64::new(0) }
    }

    /// The block of `t`, kept, or `build()`'s, kept; `None` where `build`
    /// fails (nothing kept then: the next call tries again).
    pub fn get_or_build<E: std::fmt::Display>(
        &self,
        t: &Template,
        build: impl FnOnce() -> Result<DartPlan, E>,
    ) -> Option<Arc<DartPlan>> {
        let key = TemplateKey::of(t);
        let entry = self.entries.entry(key).or_try_insert_with(|| {
            self.misses.fetch_add(1, Ordering::Relaxed);
            build().map(Arc::new).map_err(|e| e.to_string())
        });
        match entry {
            Ok(e) => Some(e.into_value()),
            Err(e) => {
                tracing::warn!(template = %t.name, error = %e, "no block: its scans decide their darts");
                None
            }
        }
    }

    /// Blocks built (or tried) so far.
    pub fn misses(&self) -> u64 {
        self.misses.load(Ordering::Relaxed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_block_is_built_once_and_a_failure_is_not_kept() {
        let t = crate::template::library::builtin().unwrap().remove(0);
        let cache = BlockCache::default();
        assert!(cache.get_or_build(&t, || Err::<DartPlan, _>("no body")).is_none());
        let plan = DartPlan { left_out: vec![("dart_x".into(), 1.0)], ..Default::default() };
        let a = cache.get_or_build(&t, || Ok::<_, String>(plan.clone())).unwrap();
        let b = cache.get_or_build(&t, || Err::<DartPlan, _>("not called")).unwrap();
        assert_eq!((*a).clone(), plan);
        assert!(Arc::ptr_eq(&a, &b));
        assert_eq!(cache.misses(), 2);
        // another document is another key
        let mut u = t.clone();
        u.name.push('2');
        assert_ne!(TemplateKey::of(&t), TemplateKey::of(&u));
    }
}
