//! Batch jobs, persisted in their own redb database (`jobs.redb`, ACID,
//! fsync on commit): a job is written before its 202 is sent, so an
//! accepted job survives a crash; at start every job not finished is
//! queued again. A job's id is the content address of its inputs (the
//! same request gives the same job and byte-identical artefacts). Scans in
//! a job's inputs are dropped from the record as soon as it ends.

use std::path::Path;

use redb::{Database, ReadableTable, TableDefinition};
use serde::{Deserialize, Serialize};

use super::problem::Problem;
use super::store::StoreError;

const JOBS: TableDefinition<&str, &[u8]> = TableDefinition::new("jobs");
const ARTEFACTS: TableDefinition<(&str, &str), &[u8]> = TableDefinition::new("artefacts");

fn db<E: std::fmt::Display>(e: E) -> StoreError {
    StoreError::Database(e.to_string())
}

/// A body of a batch job.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct JobBody {
    /// Its name: the size label of its results (1–64 characters of A–Z a–z 0–9 - _ .).
    pub name: String,
    /// The scan, GLB, base64 (standard alphabet). Emptied when the job ends.
    #[serde(default)]
    pub glb_base64: String,
    /// Its landmarks document: all, some or none of the vocabulary's points
    /// (those missing are found by registering the body model to the scan).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<Object>)]
    pub landmarks: Option<serde_json::Value>,
    /// The scan's units (default: found from its height).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub units: Option<grade3d_core::body::frame::Units>,
    /// Its up axis, `+y` or `+z` (default: found).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub up: Option<grade3d_core::body::frame::Axis>,
    /// The direction it faces, in its own axes (default: found from the feet).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub facing: Option<grade3d_core::body::frame::Axis>,
}

/// What a job grades: exactly one of a size chart and bodies, times templates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct JobSpec {
    /// Template names (the live version at submission is recorded in `versions`).
    pub templates: Vec<String>,
    /// A size chart: a JSON chart object or CSV text.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<crate::api::SizeChartInput>)]
    pub size_chart: Option<serde_json::Value>,
    /// Bodies (scans with landmarks).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub bodies: Vec<JobBody>,
    /// Base size of the grade rules.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base_size: Option<String>,
    /// The `.RUL` files' creation stamp, RFC 3339 (default: when the job runs).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(format = DateTime)]
    pub created: Option<String>,
}

/// Where a job is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum JobState {
    /// Accepted, waiting.
    Queued,
    /// Being graded.
    Running,
    /// Finished; artefacts ready.
    Done,
    /// Failed; see `error`.
    Failed,
}

impl JobState {
    /// Its name.
    pub fn as_str(self) -> &'static str {
        match self {
            JobState::Queued => "queued",
            JobState::Running => "running",
            JobState::Done => "done",
            JobState::Failed => "failed",
        }
    }
}

/// An artefact's entry in a job record.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ArtefactEntry {
    /// File name.
    pub name: String,
    /// Media type.
    pub media_type: String,
    /// Size, bytes.
    pub bytes: usize,
}

/// A job as stored.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JobRecord {
    /// Content address of the inputs.
    pub id: String,
    /// Inputs.
    pub spec: JobSpec,
    /// The template versions graded (name → version), fixed at submission.
    pub versions: Vec<(String, u32)>,
    /// State.
    pub state: JobState,
    /// The problem of a failed job.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<Problem>,
    /// Artefacts of a finished job.
    #[serde(default)]
    pub artefacts: Vec<ArtefactEntry>,
    /// The report of a finished job.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub report: Option<serde_json::Value>,
    /// Wall time per stage, ms (not part of the artefacts).
    #[serde(default)]
    pub timings_ms: std::collections::BTreeMap<String, f64>,
    /// Units of progress: the chart's sizes or the bodies, fixed at
    /// submission (issue #16: a finished job's total read 1, not 12).
    /// 0 in records stored before it was kept.
    #[serde(default)]
    pub units: usize,
}

/// The job database.
#[derive(Debug)]
pub struct JobStore {
    db: Database,
}

impl JobStore {
    /// Opens (or creates) the database at `path`.
    ///
    /// # Errors
    /// [`StoreError::Database`].
    pub fn open(path: &Path) -> Result<Self, StoreError> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(db)?;
        }
        let database = Database::create(path).map_err(db)?;
        let tx = database.begin_write().map_err(db)?;
        tx.open_table(JOBS).map_err(db)?;
        tx.open_table(ARTEFACTS).map_err(db)?;
        tx.commit().map_err(db)?;
        Ok(Self { db: database })
    }

    /// Writes `r` (durably, before returning).
    ///
    /// # Errors
    /// [`StoreError::Database`].
    pub fn put(&self, r: &JobRecord) -> Result<(), StoreError> {
        let bytes = serde_json::to_vec(r).map_err(db)?;
        let tx = self.db.begin_write().map_err(db)?;
        tx.open_table(JOBS).map_err(db)?.insert(r.id.as_str(), bytes.as_slice()).map_err(db)?;
        tx.commit().map_err(db)
    }

    /// Writes a finished job: its record and its artefacts, in one transaction.
    ///
    /// # Errors
    /// [`StoreError::Database`].
    pub fn finish(&self, r: &JobRecord, artefacts: &[(String, Vec<u8>)]) -> Result<(), StoreError> {
        let bytes = serde_json::to_vec(r).map_err(db)?;
        let tx = self.db.begin_write().map_err(db)?;
        {
            let mut a = tx.open_table(ARTEFACTS).map_err(db)?;
            for (name, b) in artefacts {
                a.insert((r.id.as_str(), name.as_str()), b.as_slice()).map_err(db)?;
            }
            tx.open_table(JOBS).map_err(db)?.insert(r.id.as_str(), bytes.as_slice()).map_err(db)?;
        }
        tx.commit().map_err(db)
    }

    /// The job `id`.
    ///
    /// # Errors
    /// [`StoreError::Database`].
    pub fn get(&self, id: &str) -> Result<Option<JobRecord>, StoreError> {
        let tx = self.db.begin_read().map_err(db)?;
        let t = tx.open_table(JOBS).map_err(db)?;
        let Some(v) = t.get(id).map_err(db)? else { return Ok(None) };
        serde_json::from_slice(v.value()).map(Some).map_err(db)
    }

    /// One artefact of job `id`.
    ///
    /// # Errors
    /// [`StoreError::Database`].
    pub fn artefact(&self, id: &str, name: &str) -> Result<Option<Vec<u8>>, StoreError> {
        let tx = self.db.begin_read().map_err(db)?;
        let t = tx.open_table(ARTEFACTS).map_err(db)?;
        Ok(t.get((id, name)).map_err(db)?.map(|v| v.value().to_vec()))
    }

    /// Every job record.
    ///
    /// # Errors
    /// [`StoreError::Database`].
    pub fn all(&self) -> Result<Vec<JobRecord>, StoreError> {
        let tx = self.db.begin_read().map_err(db)?;
        let t = tx.open_table(JOBS).map_err(db)?;
        let mut out = Vec::new();
        for row in t.iter().map_err(db)? {
            let (_, v) = row.map_err(db)?;
            out.push(serde_json::from_slice(v.value()).map_err(db)?);
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_and_artefacts_survive_reopening() {
        let dir = std::env::temp_dir().join(format!("grade3d-jobs-{}", std::process::id()));
        let path = dir.join("jobs.redb");
        let _ = std::fs::remove_file(&path);
        let spec = JobSpec {
            templates: vec!["straight-skirt".into()],
            size_chart: None,
            bodies: vec![],
            base_size: None,
            created: None,
        };
        let mut r = JobRecord {
            units: 1,
            id: "abc".into(),
            spec,
            versions: vec![("straight-skirt".into(), 1)],
            state: JobState::Queued,
            error: None,
            artefacts: vec![],
            report: None,
            timings_ms: Default::default(),
        };
        {
            let s = JobStore::open(&path).unwrap();
            s.put(&r).unwrap();
            r.state = JobState::Done;
            r.artefacts.push(ArtefactEntry { name: "a.svg".into(), media_type: "image/svg+xml".into(), bytes: 3 });
            s.finish(&r, &[("a.svg".into(), b"<s>".to_vec())]).unwrap();
        }
        let s = JobStore::open(&path).unwrap();
        assert_eq!(s.get("abc").unwrap().unwrap(), r);
        assert_eq!(s.artefact("abc", "a.svg").unwrap().unwrap(), b"<s>");
        assert!(s.artefact("abc", "b.svg").unwrap().is_none());
        assert_eq!(s.all().unwrap().len(), 1);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
