//! Content-addressed result cache: a flow's outcome under the BLAKE3 hash
//! of everything it depends on (flow, canonical inputs, template
//! documents, options), kept in memory, least recently used evicted past a
//! byte budget; entries may carry an expiry (scan results: personal data,
//! kept no longer than the configured TTL, then purged by a sweeper).

use std::collections::VecDeque;
use std::sync::{Arc, Mutex};
use std::time::Instant;

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
    pub summary: serde_json::Value,
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

/// The cache.
#[derive(Debug)]
pub struct ResultCache {
    max_bytes: usize,
    entries: Mutex<VecDeque<(String, Arc<Stored>)>>,
}

impl ResultCache {
    /// A cache holding at most `max_bytes` of artefacts.
    pub fn new(max_bytes: usize) -> Self {
        Self { max_bytes, entries: Mutex::new(VecDeque::new()) }
    }

    /// The live entry `id`, marked most recently used.
    pub fn get(&self, id: &str) -> Option<Arc<Stored>> {
        let mut e = self.entries.lock().unwrap_or_else(|p| p.into_inner());
        let pos = e.iter().position(|(k, _)| k == id)?;
        let entry = e.remove(pos)?;
        if entry.1.expires.is_some_and(|t| t <= Instant::now()) {
            return None;
        }
        let found = Arc::clone(&entry.1);
        e.push_back(entry);
        Some(found)
    }

    /// Stores `s` under `id` (replacing), evicting the least recently used
    /// past the budget; an entry larger than the budget is not kept.
    pub fn put(&self, id: String, s: Stored) -> Arc<Stored> {
        let s = Arc::new(s);
        let size = s.bytes();
        let mut e = self.entries.lock().unwrap_or_else(|p| p.into_inner());
        e.retain(|(k, _)| *k != id);
        if size > self.max_bytes {
            return s;
        }
        let mut total: usize = e.iter().map(|(_, v)| v.bytes()).sum::<usize>() + size;
        while total > self.max_bytes {
            match e.pop_front() {
                Some((_, old)) => total -= old.bytes(),
                None => break,
            }
        }
        e.push_back((id, Arc::clone(&s)));
        s
    }

    /// Drops every expired entry; returns how many.
    pub fn purge_expired(&self) -> usize {
        let now = Instant::now();
        let mut e = self.entries.lock().unwrap_or_else(|p| p.into_inner());
        let before = e.len();
        e.retain(|(_, v)| v.expires.is_none_or(|t| t > now));
        before - e.len()
    }

    /// Entries held.
    pub fn len(&self) -> usize {
        self.entries.lock().unwrap_or_else(|p| p.into_inner()).len()
    }

    /// Whether none is held.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    fn stored(n: usize, expires: Option<Instant>) -> Stored {
        Stored {
            summary: serde_json::json!({}),
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
        c.put("d".into(), stored(10, Some(Instant::now() - Duration::from_secs(1))));
        assert!(c.get("d").is_none());
        c.put("e".into(), stored(10, Some(Instant::now() - Duration::from_secs(1))));
        assert_eq!(c.purge_expired(), 1);
        c.put("huge".into(), stored(1 << 20, None));
        assert!(c.get("huge").is_none());
    }
}
