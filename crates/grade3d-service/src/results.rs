//! Content-addressed result cache: a flow's outcome under the BLAKE3 hash
//! of everything it depends on (flow, canonical inputs, template
//! documents, options), kept in memory, least recently used evicted past a
//! byte budget; entries may carry an expiry (scan results: personal data,
//! kept no longer than the configured TTL, then freed by `moka`'s
//! housekeeping on the service's tick).

use std::sync::Arc;
use std::time::{Duration, Instant};

use super::work::Artefact;

/// Hex id of the BLAKE3 hash of `parts` (each length-prefixed).
pub fn content_id(parts: &[&[u8]]) -> String {
    let mut h = blake3::Hasher::new();
    for p in parts {
        h.update(&(p.len() as u64).to_le_bytes());
        h.update(p);
    }
    h.finalize().to_hex()[..32].to_owned()
}

/// A stored outcome.
#[derive(Debug)]
pub struct Stored {
    /// The JSON answered for the flow (without `cached`).
    pub summary: crate::api::GradeResult,
    /// Its artefacts.
    pub artefacts: Vec<Artefact>,
    /// When it must be forgotten, if ever.
    pub expires: Option<Instant>,
}

impl Stored {
    fn bytes(&self) -> usize {
        self.artefacts.iter().map(|a| a.bytes.len() + a.name.len()).sum::<usize>() + 1024
    }
}

/// The cache: `moka` (issue #16: it replaced a hand-kept deque), weighed
/// in bytes ([`Stored`]'s artefacts), least recently used out past the
/// budget, each entry gone at its own expiry.
#[derive(Debug)]
pub struct ResultCache {
    entries: moka::sync::Cache<String, Arc<Stored>>,
}

/// An entry lives until its [`Stored::expires`], if it has one.
struct UntilExpiry;

impl moka::Expiry<String, Arc<Stored>> for UntilExpiry {
    fn expire_after_create(&self, _: &String, value: &Arc<Stored>, created_at: Instant) -> Option<Duration> {
        value.expires.map(|t| t.saturating_duration_since(created_at))
    }
}

impl ResultCache {
    /// A cache holding at most `max_bytes` of artefacts.
    pub fn new(max_bytes: usize) -> Self {
        let entries = moka::sync::Cache::builder()
            .max_capacity(max_bytes as u64)
            .weigher(|_: &String, v: &Arc<Stored>| u32::try_from(v.bytes()).unwrap_or(u32::MAX))
            .eviction_policy(moka::policy::EvictionPolicy::lru())
            .expire_after(UntilExpiry)
            .build();
        Self { entries }
    }

    /// The live entry `id`, marked most recently used.
    pub fn get(&self, id: &str) -> Option<Arc<Stored>> {
        // moka checks the entry's expiry on every read
        self.entries.get(id)
    }

    /// Stores `s` under `id` (replacing), evicting the least recently used
    /// past the budget; an entry larger than the budget is not kept.
    pub fn put(&self, id: String, s: Stored) -> Arc<Stored> {
        let s = Arc::new(s);
        if self.entries.policy().max_capacity().is_some_and(|budget| s.bytes() as u64 > budget) {
            self.entries.invalidate(&id);
        } else {
            self.entries.insert(id, Arc::clone(&s));
        }
        // evict now, not at the next housekeeping: the budget bounds memory
        self.entries.run_pending_tasks();
        s
    }

    /// Frees what has expired (moka's housekeeping, driven by the service's
    /// 5 s tick: scan results are personal data, and their memory is given
    /// back within a tick and moka's timer-wheel step, about 1 s, after
    /// their TTL even when no request comes; never served after it);
    /// returns how many entries went.
    pub fn purge_expired(&self) -> usize {
        let before = self.entries.entry_count();
        self.entries.run_pending_tasks();
        usize::try_from(before.saturating_sub(self.entries.entry_count())).unwrap_or(usize::MAX)
    }

    /// Entries held.
    pub fn len(&self) -> usize {
        self.entries.run_pending_tasks();
        usize::try_from(self.entries.entry_count()).unwrap_or(usize::MAX)
    }

    /// Whether none is held.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stored(n: usize, expires: Option<Instant>) -> Stored {
        Stored {
            summary: crate::api::GradeResult {
                id: "a".into(),
                flow: crate::report::Flow::Scan,
                href: "/v1/results/a".into(),
                expires_in_s: None,
                report: serde_json::Value::Null,
                timings_ms: Default::default(),
                artefacts: vec![],
                cached: false,
            },
            artefacts: vec![Artefact { name: "a".into(), media_type: "text/plain", bytes: vec![0; n] }],
            expires,
        }
    }

    #[test]
    fn ids_are_content_addresses() {
        assert_eq!(content_id(&[b"ab", b"c"]), content_id(&[b"ab", b"c"]));
        assert_ne!(content_id(&[b"ab", b"c"]), content_id(&[b"a", b"bc"]));
        assert_eq!(content_id(&[b"x"]).len(), 32);
    }

    #[test]
    fn least_recently_used_goes_first_and_expired_entries_are_gone() {
        let c = ResultCache::new(2 * 2048);
        c.put("a".into(), stored(1000, None));
        c.put("b".into(), stored(1000, None));
        assert!(c.get("a").is_some());
        c.put("c".into(), stored(1000, None));
        assert!(c.get("b").is_none(), "b was least recently used");
        assert!(c.get("a").is_some() && c.get("c").is_some());
        c.put("huge".into(), stored(1 << 20, None));
        assert!(c.get("huge").is_none(), "over the budget: not kept");
        assert!(c.get("a").is_some() && c.get("c").is_some(), "and it evicts nothing");
        // an entry past its expiry is never served (moka frees its memory on its timer
        // wheel's next step, about a second, at the housekeeping `purge_expired` runs)
        let c = ResultCache::new(1 << 20);
        c.put("d".into(), stored(10, Some(Instant::now() - Duration::from_secs(1))));
        c.put("f".into(), stored(10, Some(Instant::now() + Duration::from_secs(600))));
        assert!(c.get("d").is_none());
        c.purge_expired();
        assert!(c.get("f").is_some());
    }
}
