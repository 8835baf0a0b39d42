//! The template library's persistent store: [redb](https://docs.rs/redb), an
//! embedded, pure-Rust, ACID key-value store (copy-on-write B-trees, one
//! writer, many readers; a committed write transaction is fsynced before
//! `commit` returns, so a template answered with 201 survives `kill -9`).
//! Chosen over SQLite (a C dependency and SQL for what is a two-table
//! key-value job) and sled (unmaintained, no stable on-disk format).
//!
//! Layout: `versions: (name, version) → template JSON` keeps every
//! version; `current: name → version` points at the live one; `meta`
//! records that the built-in templates were seeded (so a library whose
//! built-ins were deleted stays that way after a restart); `bodies:
//! content id → scan` keeps the scans templates were designed on
//! ([`StoredScan`]; issue #18: a template authored on an avatar is edited
//! there), written before the template that names them.
//!
//! Every template is validated ([`Template::from_json`]) before it is
//! written. Failure modes: [`StoreError`].

use std::path::Path;

use redb::{Database, ReadableTable, TableDefinition};

use crate::template::format::{Template, TemplateError};

const VERSIONS: TableDefinition<(&str, u32), &[u8]> = TableDefinition::new("versions");
const CURRENT: TableDefinition<&str, u32> = TableDefinition::new("current");
const META: TableDefinition<&str, u64> = TableDefinition::new("meta");
const BODIES: TableDefinition<&str, &[u8]> = TableDefinition::new("bodies");
const SEEDED: &str = "seeded_builtins";

/// A scan kept as a design body: what was uploaded, so that it is read
/// again exactly as it was (repaired, framed, landmarked, derived).
#[derive(Debug, Clone, PartialEq)]
pub struct StoredScan {
    /// The GLB.
    pub glb: Vec<u8>,
    /// Its landmarks JSON, if given.
    pub landmarks: Option<String>,
    /// What the upload stated of its units and axes.
    pub hints: crate::body::frame::FrameHints,
}

#[derive(serde::Serialize, serde::Deserialize)]
struct ScanHeader {
    landmarks: Option<String>,
    hints: crate::body::frame::FrameHints,
}

impl StoredScan {
    /// `u32` (little-endian) header length, the header (landmarks and
    /// hints, JSON), the GLB.
    fn to_bytes(&self) -> Result<Vec<u8>, StoreError> {
        let header =
            serde_json::to_vec(&ScanHeader { landmarks: self.landmarks.clone(), hints: self.hints }).map_err(db)?;
        let len = u32::try_from(header.len()).map_err(db)?;
        let mut out = Vec::with_capacity(4 + header.len() + self.glb.len());
        out.extend_from_slice(&len.to_le_bytes());
        out.extend_from_slice(&header);
        out.extend_from_slice(&self.glb);
        Ok(out)
    }

    /// The content id it is kept under: of its stored bytes (GLB, landmarks
    /// and hints alike).
    ///
    /// # Errors
    /// [`StoreError::Database`] (a header that cannot be written).
    pub fn content_id(&self) -> Result<String, StoreError> {
        Ok(crate::results::content_id(&[b"design-scan", &self.to_bytes()?]))
    }

    fn from_bytes(bytes: &[u8]) -> Result<Self, StoreError> {
        let corrupt = || StoreError::Database("a stored scan is corrupt".into());
        let len = u32::from_le_bytes(bytes.get(..4).ok_or_else(corrupt)?.try_into().map_err(|_| corrupt())?);
        let end = 4usize.checked_add(usize::try_from(len).map_err(|_| corrupt())?).ok_or_else(corrupt)?;
        let header: ScanHeader = serde_json::from_slice(bytes.get(4..end).ok_or_else(corrupt)?).map_err(db)?;
        Ok(Self { glb: bytes[end..].to_vec(), landmarks: header.landmarks, hints: header.hints })
    }
}

/// Why a store operation failed.
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    /// The database could not be opened, read or written.
    #[error("template store: {0}")]
    Database(String),
    /// The template is invalid.
    #[error(transparent)]
    Invalid(#[from] TemplateError),
    /// No template of that name (or version).
    #[error("no template '{name}'{}", version.map(|v| format!(" version {v}")).unwrap_or_default())]
    NotFound {
        /// Name asked for.
        name: String,
        /// Version asked for.
        version: Option<u32>,
    },
    /// A create for a name that exists.
    #[error("template '{0}' exists; replace it with PUT to make a new version")]
    Exists(String),
    /// An edit of a version that is no longer the live one.
    #[error("template '{name}' is at version {live}, not {expected}: edit it again")]
    Stale {
        /// The name.
        name: String,
        /// The version the edit was made on.
        expected: u32,
        /// The live version.
        live: u32,
    },
    /// The body's name differs from the path's.
    #[error("template name '{body}' differs from the name in the path '{path}'")]
    NameMismatch {
        /// Name in the path.
        path: String,
        /// Name in the body.
        body: String,
    },
}

fn db<E: std::fmt::Display>(e: E) -> StoreError {
    StoreError::Database(e.to_string())
}

/// A template's name and live version.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize, utoipa::ToSchema)]
pub struct Entry {
    /// Template name.
    pub name: String,
    /// Live version (1 for the first).
    pub version: u32,
}

/// The template store.
#[derive(Debug)]
pub struct TemplateStore {
    db: Database,
}

impl TemplateStore {
    /// Opens (or creates) the store at `path` and seeds `builtins` on first start.
    ///
    /// # Errors
    /// [`StoreError::Database`].
    pub fn open(path: &Path, builtins: &[Template]) -> Result<Self, StoreError> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(db)?;
        }
        let db = Database::create(path).map_err(db)?;
        let store = Self { db };
        store.seed(builtins)?;
        Ok(store)
    }

    fn seed(&self, builtins: &[Template]) -> Result<(), StoreError> {
        let tx = self.db.begin_write().map_err(db)?;
        {
            let mut meta = tx.open_table(META).map_err(db)?;
            let seeded = meta.get(SEEDED).map_err(db)?.is_some();
            let mut versions = tx.open_table(VERSIONS).map_err(db)?;
            let mut current = tx.open_table(CURRENT).map_err(db)?;
            if !seeded {
                for t in builtins {
                    if current.get(t.name.as_str()).map_err(db)?.is_none() {
                        versions.insert((t.name.as_str(), 1), t.to_json().as_bytes()).map_err(db)?;
                        current.insert(t.name.as_str(), 1).map_err(db)?;
                    }
                }
                meta.insert(SEEDED, 1).map_err(db)?;
            }
        }
        tx.commit().map_err(db)
    }

    /// Every live template, by name.
    ///
    /// # Errors
    /// [`StoreError::Database`].
    pub fn list(&self) -> Result<Vec<Entry>, StoreError> {
        let tx = self.db.begin_read().map_err(db)?;
        let current = tx.open_table(CURRENT).map_err(db)?;
        current
            .iter()
            .map_err(db)?
            .map(|r| r.map(|(k, v)| Entry { name: k.value().to_string(), version: v.value() }).map_err(db))
            .collect()
    }

    /// Every live template, parsed, in name order.
    ///
    /// # Errors
    /// [`StoreError::Database`]; [`StoreError::Invalid`] for a stored
    /// document that no longer parses.
    pub fn live(&self) -> Result<Vec<Template>, StoreError> {
        self.list()?.iter().map(|e| self.get(&e.name, None).map(|(_, t)| t)).collect()
    }

    /// A template (the live version, or `version`) as stored JSON.
    ///
    /// # Errors
    /// [`StoreError::NotFound`], [`StoreError::Database`].
    pub fn get_json(&self, name: &str, version: Option<u32>) -> Result<(u32, String), StoreError> {
        let not_found = || StoreError::NotFound { name: name.to_string(), version };
        let tx = self.db.begin_read().map_err(db)?;
        let v = match version {
            Some(v) => v,
            None => tx.open_table(CURRENT).map_err(db)?.get(name).map_err(db)?.ok_or_else(not_found)?.value(),
        };
        let versions = tx.open_table(VERSIONS).map_err(db)?;
        let bytes = versions.get((name, v)).map_err(db)?.ok_or_else(not_found)?;
        Ok((v, String::from_utf8_lossy(bytes.value()).into_owned()))
    }

    /// A template, parsed and validated.
    ///
    /// # Errors
    /// As [`TemplateStore::get_json`]; [`StoreError::Invalid`] if the stored JSON no longer validates.
    pub fn get(&self, name: &str, version: Option<u32>) -> Result<(u32, Template), StoreError> {
        let (v, json) = self.get_json(name, version)?;
        Ok((v, Template::from_json(&json)?))
    }

    /// Stores `json` as a new template (`create`) or a new version of an existing one.
    /// Returns the version written. Durable when this returns.
    ///
    /// # Errors
    /// [`StoreError::Invalid`], [`StoreError::Exists`] (create of an existing name),
    /// [`StoreError::NotFound`] (replace of a missing name), [`StoreError::NameMismatch`].
    pub fn put(&self, path_name: Option<&str>, json: &str, create: bool) -> Result<Entry, StoreError> {
        let t = Template::from_json(json)?;
        if let Some(p) = path_name.filter(|p| *p != t.name) {
            return Err(StoreError::NameMismatch { path: p.to_string(), body: t.name.clone() });
        }
        self.write(t, create, None)
    }

    /// Stores `t`, an edit of version `based_on`, as the next version of
    /// its name, its `version` field set to the number it is stored under.
    /// Durable when this returns.
    ///
    /// # Errors
    /// [`StoreError::Stale`] when `based_on` is no longer the live version
    /// (another write came first); [`StoreError::NotFound`] for a deleted
    /// name; [`StoreError::Invalid`], [`StoreError::Database`].
    pub fn put_edit(&self, t: &Template, based_on: u32) -> Result<Entry, StoreError> {
        // the schema too, as every stored document
        self.write(Template::from_json(&t.to_json())?, false, Some(based_on))
    }

    /// Writes `t` as a new version (`create`: the first), `based_on` the
    /// live version it must replace, if any (module docs).
    fn write(&self, mut t: Template, create: bool, based_on: Option<u32>) -> Result<Entry, StoreError> {
        let tx = self.db.begin_write().map_err(db)?;
        let version;
        {
            let mut current = tx.open_table(CURRENT).map_err(db)?;
            let live = current.get(t.name.as_str()).map_err(db)?.map(|v| v.value());
            let mut versions = tx.open_table(VERSIONS).map_err(db)?;
            // a new version number above every version ever stored under the name
            let highest = {
                let last = versions.range((t.name.as_str(), 0)..=(t.name.as_str(), u32::MAX)).map_err(db)?.next_back();
                match last {
                    Some(r) => r.map_err(db)?.0.value().1,
                    None => 0,
                }
            };
            match (create, live) {
                (true, Some(_)) => return Err(StoreError::Exists(t.name.clone())),
                (false, None) => return Err(StoreError::NotFound { name: t.name.clone(), version: None }),
                _ => {}
            }
            if let Some(expected) = based_on.filter(|&b| live != Some(b)) {
                return Err(StoreError::Stale { name: t.name.clone(), expected, live: live.unwrap_or(0) });
            }
            version = highest + 1;
            if based_on.is_some() {
                t.version = version;
            }
            versions.insert((t.name.as_str(), version), t.to_json().as_bytes()).map_err(db)?;
            current.insert(t.name.as_str(), version).map_err(db)?;
        }
        tx.commit().map_err(db)?;
        Ok(Entry { name: t.name, version })
    }

    /// Keeps `scan` under its content id `id` (a second put of the same id
    /// writes nothing), durably.
    ///
    /// # Errors
    /// [`StoreError::Database`].
    pub fn put_scan(&self, id: &str, scan: &StoredScan) -> Result<(), StoreError> {
        let tx = self.db.begin_write().map_err(db)?;
        {
            let mut bodies = tx.open_table(BODIES).map_err(db)?;
            if bodies.get(id).map_err(db)?.is_none() {
                bodies.insert(id, scan.to_bytes()?.as_slice()).map_err(db)?;
            }
        }
        tx.commit().map_err(db)
    }

    /// The scan kept under `id`, if any.
    ///
    /// # Errors
    /// [`StoreError::Database`].
    pub fn get_scan(&self, id: &str) -> Result<Option<StoredScan>, StoreError> {
        let tx = self.db.begin_read().map_err(db)?;
        let bodies = match tx.open_table(BODIES) {
            Ok(t) => t,
            Err(redb::TableError::TableDoesNotExist(_)) => return Ok(None),
            Err(e) => return Err(db(e)),
        };
        let value = bodies.get(id).map_err(db)?;
        value.map(|v| StoredScan::from_bytes(v.value())).transpose()
    }

    /// Deletes a template (every version stays readable by number; the name is freed).
    ///
    /// # Errors
    /// [`StoreError::NotFound`], [`StoreError::Database`].
    pub fn delete(&self, name: &str) -> Result<(), StoreError> {
        let tx = self.db.begin_write().map_err(db)?;
        {
            let mut current = tx.open_table(CURRENT).map_err(db)?;
            if current.remove(name).map_err(db)?.is_none() {
                return Err(StoreError::NotFound { name: name.to_string(), version: None });
            }
        }
        tx.commit().map_err(db)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::template::library::builtin;

    fn temp(name: &str) -> std::path::PathBuf {
        let p = std::env::temp_dir().join(format!("grade3d-store-{}-{name}.redb", std::process::id()));
        let _ = std::fs::remove_file(&p);
        p
    }

    #[test]
    fn a_design_scan_is_kept_once_and_read_back_after_a_reopen() {
        let path = temp("scans");
        let store = TemplateStore::open(&path, &[]).expect("open");
        assert_eq!(store.get_scan("abc").unwrap(), None, "no table yet");
        let scan = StoredScan {
            glb: b"glTF\x02\0\0\0 not really".to_vec(),
            landmarks: Some("{\"points\": {}}".into()),
            hints: crate::body::frame::FrameHints {
                units: Some(crate::body::frame::Units::Millimetres),
                ..Default::default()
            },
        };
        store.put_scan("abc", &scan).unwrap();
        store.put_scan("abc", &StoredScan { glb: vec![1], landmarks: None, hints: Default::default() }).unwrap();
        drop(store);
        let store = TemplateStore::open(&path, &[]).expect("reopen");
        assert_eq!(store.get_scan("abc").unwrap(), Some(scan), "the first put kept");
        assert_eq!(store.get_scan("abd").unwrap(), None);
        assert!(StoredScan::from_bytes(&[9, 0, 0, 0, b'{']).is_err(), "a short header is named, not a panic");
    }

    #[test]
    fn seed_create_replace_delete_and_reopen() {
        let path = temp("crud");
        let lib = builtin().expect("library");
        let store = TemplateStore::open(&path, &lib).expect("open");
        let names: Vec<String> = store.list().unwrap().into_iter().map(|e| e.name).collect();
        assert_eq!(names, ["a-line-skirt", "fitted-bodice", "straight-skirt", "trousers"]);
        let (v, skirt) = store.get("straight-skirt", None).unwrap();
        assert_eq!((v, &skirt), (1, &lib[0]));
        // replace: version 2; the old version stays readable
        let mut edited = skirt.clone();
        edited.description = "shorter".into();
        let e = store.put(Some("straight-skirt"), &edited.to_json(), false).unwrap();
        assert_eq!(e.version, 2);
        assert_eq!(store.get("straight-skirt", Some(1)).unwrap().1, skirt);
        // create of an existing name, replace of a missing one, name mismatch, invalid JSON
        assert!(matches!(store.put(None, &edited.to_json(), true), Err(StoreError::Exists(_))));
        let mut other = edited.clone();
        other.name = "mini-skirt".into();
        assert!(matches!(store.put(None, &other.to_json(), false), Err(StoreError::NotFound { .. })));
        assert!(matches!(store.put(Some("x"), &other.to_json(), true), Err(StoreError::NameMismatch { .. })));
        assert!(matches!(store.put(None, "{}", true), Err(StoreError::Invalid(_))));
        assert_eq!(store.put(None, &other.to_json(), true).unwrap().version, 1);
        store.delete("trousers").unwrap();
        assert!(matches!(store.delete("trousers"), Err(StoreError::NotFound { .. })));
        drop(store);
        // reopen: deleted built-ins are not re-seeded, writes persisted
        let store = TemplateStore::open(&path, &lib).expect("reopen");
        let entries = store.list().unwrap();
        assert_eq!(
            entries,
            vec![
                Entry { name: "a-line-skirt".into(), version: 1 },
                Entry { name: "fitted-bodice".into(), version: 1 },
                Entry { name: "mini-skirt".into(), version: 1 },
                Entry { name: "straight-skirt".into(), version: 2 },
            ]
        );
        let _ = std::fs::remove_file(&path);
    }

    #[test]
    fn an_edit_is_stored_as_the_next_version_numbered_as_stored_and_a_stale_one_is_refused() {
        let path = temp("edit");
        let lib = builtin().expect("library");
        let store = TemplateStore::open(&path, &lib).expect("open");
        let (v, skirt) = store.get("straight-skirt", None).unwrap();
        let mut edited = skirt.clone();
        edited.description = "edited".into();
        edited.version = 77;
        let e = store.put_edit(&edited, v).unwrap();
        assert_eq!(e.version, v + 1);
        let (_, back) = store.get("straight-skirt", Some(e.version)).unwrap();
        assert_eq!(back, Template { version: v + 1, ..edited.clone() });
        // an edit of version 1 after version 2 was stored: refused, nothing written
        match store.put_edit(&edited, v) {
            Err(StoreError::Stale { expected, live, .. }) => assert_eq!((expected, live), (v, v + 1)),
            other => panic!("{other:?}"),
        }
        assert_eq!(store.get("straight-skirt", None).unwrap().0, v + 1);
        let _ = std::fs::remove_file(&path);
    }
}
