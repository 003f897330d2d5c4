//! The durable store: one redb database in the data dir holding sites (maps as uploaded), plan records, plan
//! documents as computed (version 1), the corrections made to them since, and the history of status
//! transitions. The current version of a plan is its document with its corrections applied in order.
//!
//! Every engine event's writes are one committed transaction ([`Store::commit`]), so what the API acknowledged
//! survives a kill -9 and an event's writes land all or none. Only the engine thread writes; reads happen at
//! start-up. A failed write is classified ([`fault`]: full, read-only, other I/O); after an I/O failure redb
//! refuses everything until the database is reopened, which [`Store::recover`] does (redb repairs the file if
//! the failure interrupted a commit) before it probes with a small write.

pub mod fault;

use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

use redb::{Database, ReadableDatabase, ReadableTable, TableDefinition};
use serde::{Serialize, de::DeserializeOwned};
use shift_engine::{Command, CoverageRecord, MissionRecord, PlanRecord, SiteRecord};
use shift_proto::{CorrectionDoc, PlanDocument};

use self::fault::{FaultKind, StoreError};
use crate::error::{Context, Result};

const SITES: TableDefinition<'_, &str, &[u8]> = TableDefinition::new("sites");
const PLANS: TableDefinition<'_, &str, &[u8]> = TableDefinition::new("plans");
const RESULTS: TableDefinition<'_, &str, &[u8]> = TableDefinition::new("results");
/// (plan id, transition number) → `{"status", "at_ms", "error"}`.
const TRANSITIONS: TableDefinition<'_, (&str, u32), &[u8]> = TableDefinition::new("transitions");
/// (plan id, version produced) → correction JSON.
const CORRECTIONS: TableDefinition<'_, (&str, u64), &[u8]> = TableDefinition::new("corrections");
/// Mission id → mission record.
const MISSIONS: TableDefinition<'_, &str, &[u8]> = TableDefinition::new("missions");
/// `site/NAME` or `mission/ID` → measured coverage raster (run lengths).
const COVERAGE: TableDefinition<'_, &str, &[u8]> = TableDefinition::new("coverage");
/// Small bookkeeping: `probe` → the time of the last recovery probe.
const META: TableDefinition<'_, &str, &[u8]> = TableDefinition::new("meta");

/// The database handle.
#[derive(Debug)]
pub struct Store {
    path: PathBuf,
    /// The page cache, bytes (kept for reopening).
    cache_bytes: usize,
    /// `None` after a reopen failed; the next write tries again.
    db: Mutex<Option<Database>>,
    /// An I/O error latched redb (or the reopen failed): reopen before the next write.
    broken: Mutex<Option<StoreError>>,
}

/// One write of an engine event, as [`Store::commit`] takes them.
#[derive(Debug, Clone, Copy)]
pub enum Write<'a> {
    /// A site as uploaded.
    Site(&'a SiteRecord),
    /// A plan record (its status appended to the history when it changed).
    Plan(&'a PlanRecord),
    /// A plan's computed document.
    Result {
        /// Plan id.
        plan_id: &'a str,
        /// The document.
        doc: &'a PlanDocument,
    },
    /// A settled plan forgotten (`retain_plans`): its record, document, corrections and history.
    Forget(&'a str),
    /// A plan's new document (a replan) with its record; the corrections of earlier versions are dropped.
    Replace {
        /// The record at the new version.
        record: &'a PlanRecord,
        /// The document.
        doc: &'a PlanDocument,
    },
    /// A mission record.
    Mission(&'a MissionRecord),
    /// A measured coverage raster.
    Coverage(&'a CoverageRecord),
    /// A correction and the plan record at its version.
    Correction {
        /// The record at the new version.
        record: &'a PlanRecord,
        /// The correction.
        correction: &'a CorrectionDoc,
    },
}

impl<'a> Write<'a> {
    /// The write a command asks for, if it asks for one.
    pub fn of(cmd: &'a Command) -> Option<Self> {
        Some(match cmd {
            Command::StoreSite(site) => Self::Site(site),
            Command::StorePlan(rec) => Self::Plan(rec),
            Command::StoreResult { plan_id, doc } => Self::Result { plan_id, doc },
            Command::StoreCorrection { record, correction, .. } => Self::Correction { record, correction },
            Command::ForgetPlan { plan_id } => Self::Forget(plan_id),
            Command::StoreMission(rec) => Self::Mission(rec),
            Command::ReplacePlanDoc { record, doc } => Self::Replace { record, doc },
            Command::StoreCoverage(rec) => Self::Coverage(rec),
            _ => return None,
        })
    }
}

#[derive(Serialize, serde::Deserialize)]
struct Transition {
    status: shift_proto::PlanStatus,
    at_ms: u64,
    #[serde(skip_serializing_if = "Option::is_none")]
    error: Option<String>,
}

fn decode<T: DeserializeOwned>(what: &str, key: &str, bytes: &[u8]) -> Result<T> {
    serde_json::from_slice(bytes).with_context(|| format!("store: {what} {key:?} is unreadable"))
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// The page cache when none is configured, bytes ([`crate::config::StoreConfig::cache_mb`]'s default).
pub const DEFAULT_CACHE_BYTES: usize = 64 << 20;

/// Opens `path` with a page cache of `cache_bytes` and makes sure every table exists.
fn open_db(path: &Path, cache_bytes: usize) -> Result<Database, StoreError> {
    let db = redb::Builder::new().set_cache_size(cache_bytes).create(path)?;
    let txn = db.begin_write()?;
    txn.open_table(SITES)?;
    txn.open_table(PLANS)?;
    txn.open_table(RESULTS)?;
    txn.open_table(TRANSITIONS)?;
    txn.open_table(CORRECTIONS)?;
    txn.open_table(META)?;
    txn.open_table(MISSIONS)?;
    txn.open_table(COVERAGE)?;
    txn.commit()?;
    Ok(db)
}

impl Store {
    /// Opens (or creates) `DIR/shift.redb`, creating the folder and every table, with the default page cache.
    pub fn open(data_dir: &Path) -> Result<Self> {
        Self::open_with_cache(data_dir, DEFAULT_CACHE_BYTES)
    }

    /// As [`Store::open`], with a page cache of at most `cache_bytes` (`[store] cache_mb`).
    pub fn open_with_cache(data_dir: &Path, cache_bytes: usize) -> Result<Self> {
        std::fs::create_dir_all(data_dir).with_context(|| format!("creating data dir {}", data_dir.display()))?;
        let path = data_dir.join("shift.redb");
        let db = open_db(&path, cache_bytes).with_context(|| format!("opening store {}", path.display()))?;
        Ok(Self {
            path,
            cache_bytes,
            db: Mutex::new(Some(db)),
            broken: Mutex::new(None),
        })
    }

    /// Commits `writes` in one transaction: all of them or, on error, none.
    pub fn commit(&self, writes: &[Write<'_>]) -> Result<(), StoreError> {
        let mut db = lock(&self.db);
        self.reopen_if_broken(&mut db)?;
        let result = Self::write_all(db.as_ref(), writes);
        if let Err(e) = &result
            && e.kind.needs_reopen()
        {
            *lock(&self.broken) = Some(e.clone());
        }
        result
    }

    /// After a failure: reopens the database (redb repairs an interrupted commit) and commits a small probe
    /// write. `Ok` means writes work again.
    pub fn recover(&self, now_ms: u64) -> Result<(), StoreError> {
        let probe = now_ms.to_le_bytes();
        let mut db = lock(&self.db);
        self.reopen_if_broken(&mut db)?;
        let result = (|| -> Result<(), StoreError> {
            let db = db
                .as_ref()
                .ok_or_else(|| StoreError::new(FaultKind::Io, "the store is closed"))?;
            let txn = db.begin_write()?;
            txn.open_table(META)?.insert("probe", probe.as_slice())?;
            txn.commit()?;
            Ok(())
        })();
        if let Err(e) = &result
            && e.kind.needs_reopen()
        {
            *lock(&self.broken) = Some(e.clone());
        }
        result
    }

    fn reopen_if_broken(&self, db: &mut Option<Database>) -> Result<(), StoreError> {
        let mut broken = lock(&self.broken);
        if broken.is_none() {
            return Ok(());
        }
        // redb releases the file when the handle drops; only then can it be opened again.
        drop(db.take());
        let reopened = open_db(&self.path, self.cache_bytes)?;
        tracing::info!(path = %self.path.display(), "store reopened after a failed write");
        *db = Some(reopened);
        *broken = None;
        Ok(())
    }

    fn write_all(db: Option<&Database>, writes: &[Write<'_>]) -> Result<(), StoreError> {
        let db = db.ok_or_else(|| StoreError::new(FaultKind::Io, "the store is closed"))?;
        let txn = db.begin_write()?;
        for w in writes {
            match *w {
                Write::Site(site) => {
                    let bytes = serde_json::to_vec(site)?;
                    txn.open_table(SITES)?.insert(site.site.as_str(), bytes.as_slice())?;
                }
                Write::Plan(rec) => write_plan(&txn, rec)?,
                Write::Result { plan_id, doc } => {
                    let bytes = serde_json::to_vec(doc)?;
                    txn.open_table(RESULTS)?.insert(plan_id, bytes.as_slice())?;
                }
                Write::Forget(plan_id) => forget_plan(&txn, plan_id)?,
                Write::Replace { record, doc } => {
                    let id = record.plan_id.as_str();
                    txn.open_table(RESULTS)?
                        .insert(id, serde_json::to_vec(doc)?.as_slice())?;
                    txn.open_table(CORRECTIONS)?
                        .retain_in((id, 0)..=(id, u64::MAX), |_, _| false)?;
                    write_plan(&txn, record)?;
                }
                Write::Mission(rec) => {
                    let bytes = serde_json::to_vec(rec)?;
                    txn.open_table(MISSIONS)?
                        .insert(rec.mission_id.as_str(), bytes.as_slice())?;
                }
                Write::Coverage(rec) => {
                    let bytes = serde_json::to_vec(rec)?;
                    txn.open_table(COVERAGE)?
                        .insert(rec.key.store_key().as_str(), bytes.as_slice())?;
                }
                Write::Correction { record, correction } => {
                    let bytes = serde_json::to_vec(correction)?;
                    txn.open_table(CORRECTIONS)?
                        .insert((correction.plan_id.as_str(), correction.version), bytes.as_slice())?;
                    write_plan(&txn, record)?;
                }
            }
        }
        txn.commit()?;
        Ok(())
    }

    /// Persists a site.
    pub fn put_site(&self, site: &SiteRecord) -> Result<()> {
        Ok(self.commit(&[Write::Site(site)])?)
    }

    /// Persists a plan record and appends its status to the plan's history when it changed.
    pub fn put_plan(&self, rec: &PlanRecord) -> Result<()> {
        Ok(self.commit(&[Write::Plan(rec)])?)
    }

    /// Persists a correction and the plan record at its version in one transaction.
    pub fn put_correction(&self, record: &PlanRecord, correction: &CorrectionDoc) -> Result<()> {
        Ok(self.commit(&[Write::Correction { record, correction }])?)
    }

    /// Persists a plan document.
    pub fn put_result(&self, plan_id: &str, doc: &PlanDocument) -> Result<()> {
        Ok(self.commit(&[Write::Result { plan_id, doc }])?)
    }

    fn read(&self) -> Result<redb::ReadTransaction> {
        let db = lock(&self.db);
        let db = db.as_ref().context("store: closed after a failed reopen")?;
        Ok(db.begin_read().map_err(StoreError::from)?)
    }

    /// A plan's corrections in version order.
    pub fn corrections(&self, plan_id: &str) -> Result<Vec<CorrectionDoc>> {
        let txn = self.read()?;
        let t = txn.open_table(CORRECTIONS).map_err(StoreError::from)?;
        let mut out = Vec::new();
        for item in t.range((plan_id, 0)..=(plan_id, u64::MAX)).map_err(StoreError::from)? {
            let (_, v) = item.map_err(StoreError::from)?;
            out.push(decode("correction", plan_id, v.value())?);
        }
        Ok(out)
    }

    /// A plan's current document: as computed, with its corrections applied in order. A correction that does
    /// not apply (a damaged store) ends the chain there, with an error in the log.
    pub fn current(&self, plan_id: &str) -> Result<Option<PlanDocument>> {
        let Some(mut doc) = self.result(plan_id)? else {
            return Ok(None);
        };
        for c in self.corrections(plan_id)? {
            match c.apply(&doc) {
                Ok(next) => doc = next,
                Err(e) => {
                    tracing::error!(plan_id, version = c.version, "stored correction does not apply: {e}");
                    break;
                }
            }
        }
        Ok(Some(doc))
    }

    /// Every site.
    pub fn sites(&self) -> Result<Vec<SiteRecord>> {
        self.all(SITES, "site")
    }

    /// Every plan record.
    pub fn plans(&self) -> Result<Vec<PlanRecord>> {
        self.all(PLANS, "plan")
    }

    /// Every mission record.
    pub fn missions(&self) -> Result<Vec<MissionRecord>> {
        self.all(MISSIONS, "mission")
    }

    /// Every measured coverage raster.
    pub fn coverage(&self) -> Result<Vec<CoverageRecord>> {
        self.all(COVERAGE, "coverage raster")
    }

    /// A plan's document.
    pub fn result(&self, plan_id: &str) -> Result<Option<PlanDocument>> {
        let txn = self.read()?;
        let t = txn.open_table(RESULTS).map_err(StoreError::from)?;
        t.get(plan_id)
            .map_err(StoreError::from)?
            .map(|g| decode("result", plan_id, g.value()))
            .transpose()
    }

    /// A plan's status history: (status, at_ms) in order.
    pub fn history(&self, plan_id: &str) -> Result<Vec<(shift_proto::PlanStatus, u64)>> {
        let txn = self.read()?;
        let t = txn.open_table(TRANSITIONS).map_err(StoreError::from)?;
        let mut out = Vec::new();
        for item in t.range((plan_id, 0)..=(plan_id, u32::MAX)).map_err(StoreError::from)? {
            let (_, v) = item.map_err(StoreError::from)?;
            let tr: Transition = decode("transition", plan_id, v.value())?;
            out.push((tr.status, tr.at_ms));
        }
        Ok(out)
    }

    fn all<T: DeserializeOwned>(&self, def: TableDefinition<'_, &str, &[u8]>, what: &str) -> Result<Vec<T>> {
        let txn = self.read()?;
        let t = txn.open_table(def).map_err(StoreError::from)?;
        let mut out = Vec::new();
        for item in t.iter().map_err(StoreError::from)? {
            let (k, v) = item.map_err(StoreError::from)?;
            out.push(decode(what, k.value(), v.value())?);
        }
        Ok(out)
    }
}

/// Removes every row of a plan inside `txn`.
fn forget_plan(txn: &redb::WriteTransaction, plan_id: &str) -> Result<(), StoreError> {
    txn.open_table(PLANS)?.remove(plan_id)?;
    txn.open_table(RESULTS)?.remove(plan_id)?;
    txn.open_table(TRANSITIONS)?
        .retain_in((plan_id, 0)..=(plan_id, u32::MAX), |_, _| false)?;
    txn.open_table(CORRECTIONS)?
        .retain_in((plan_id, 0)..=(plan_id, u64::MAX), |_, _| false)?;
    Ok(())
}

/// Writes a plan record and appends its status to the history when it changed, inside `txn`.
fn write_plan(txn: &redb::WriteTransaction, rec: &PlanRecord) -> Result<(), StoreError> {
    let bytes = serde_json::to_vec(rec)?;
    let mut plans = txn.open_table(PLANS)?;
    let previous = match plans.get(rec.plan_id.as_str())? {
        Some(g) => Some(
            serde_json::from_slice::<PlanRecord>(g.value())
                .map_err(|e| StoreError::new(FaultKind::Data, format!("plan {:?} is unreadable: {e}", rec.plan_id)))?,
        ),
        None => None,
    };
    plans.insert(rec.plan_id.as_str(), bytes.as_slice())?;
    let mut history = txn.open_table(TRANSITIONS)?;
    let last = history
        .range((rec.plan_id.as_str(), 0)..=(rec.plan_id.as_str(), u32::MAX))?
        .next_back()
        .transpose()?
        .map(|(k, _)| k.value().1);
    if previous.as_ref().is_none_or(|p| p.status != rec.status) {
        let t = Transition {
            status: rec.status,
            at_ms: rec.updated_ms,
            error: rec.error.clone(),
        };
        let n = last.map_or(0, |n| n + 1);
        history.insert((rec.plan_id.as_str(), n), serde_json::to_vec(&t)?.as_slice())?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use shift_engine::MapSource;
    use shift_proto::{PlanRequest, PlanStatus, RobotSpec};

    use super::*;

    fn record(id: &str, status: PlanStatus, at: u64) -> PlanRecord {
        PlanRecord {
            plan_id: id.into(),
            seq: 1,
            request: PlanRequest {
                site: "s".into(),
                start: [0.0, 0.0],
                robot: RobotSpec {
                    radius: 0.1,
                    footprint: None,
                    tool_width: 0.2,
                    v_min: 0.1,
                    v_max: 1.0,
                    a_max: 0.5,
                },
                attribute: None,
                region: None,
                options: None,
                objective: None,
                snap_start_m: None,
            },
            status,
            progress: 0.0,
            version: 0,
            regions_ready: 0,
            metrics: None,
            error: None,
            warnings: vec![],
            robot: None,
            driven_fraction: 0.0,
            missed: Vec::new(),
            watch: None,
            progress_jumps: Vec::new(),
            mission: None,
            attempts: 0,
            created_ms: 0,
            updated_ms: at,
        }
    }

    #[test]
    fn records_survive_reopening_and_history_keeps_transitions() {
        let dir = tempfile::tempdir().expect("tempdir");
        {
            let store = Store::open(dir.path()).expect("open");
            store
                .put_site(&SiteRecord {
                    site: "s".into(),
                    source: MapSource::Json { text: "{}".into() },
                    updated_ms: 5,
                })
                .expect("site");
            store.put_plan(&record("p-1", PlanStatus::Queued, 1)).expect("queued");
            store
                .put_plan(&record("p-1", PlanStatus::Queued, 2))
                .expect("same status");
            store
                .put_plan(&record("p-1", PlanStatus::Planning, 3))
                .expect("planning");
            store
                .put_plan(&record("p-10", PlanStatus::Queued, 4))
                .expect("other plan");
        }
        let store = Store::open(dir.path()).expect("reopen");
        assert_eq!(store.sites().expect("sites").len(), 1);
        let plans = store.plans().expect("plans");
        assert_eq!(plans.len(), 2);
        assert_eq!(
            store.history("p-1").expect("history"),
            vec![(PlanStatus::Queued, 1), (PlanStatus::Planning, 3)]
        );
        assert_eq!(store.history("p-10").expect("history").len(), 1);
        assert!(store.result("p-1").expect("read").is_none());
    }

    #[test]
    fn corrections_commit_with_their_record_and_replay_to_the_current_version() {
        use shift_proto::{CorrectionDoc, CorrectionReason, PlanMetricsDoc, WaypointDoc, WaypointKindDoc};
        let wp = |x: f64| WaypointDoc {
            x,
            y: 0.0,
            z: 0.0,
            v: 0.5,
            t: x,
            kind: WaypointKindDoc::Cover,
            region: None,
        };
        let doc = PlanDocument {
            plan_id: "p-1".into(),
            version: 1,
            frame: "map".into(),
            waypoints: (0..5).map(|i| wp(i as f64)).collect(),
            regions: vec![],
            metrics: PlanMetricsDoc::default(),
        };
        let correction = |base: u64, from: usize, to: usize, x: f64| CorrectionDoc {
            plan_id: "p-1".into(),
            robot: "r1".into(),
            base_version: base,
            version: base + 1,
            from,
            to,
            waypoints: vec![wp(x)],
            reason: CorrectionReason::Obstacle,
            dt_after_s: 0.5,
            skipped: vec![],
            compute_us: 7,
        };
        let dir = tempfile::tempdir().expect("tempdir");
        let c1 = correction(1, 1, 2, 1.5);
        let c2 = correction(2, 3, 5, 9.0);
        {
            let store = Store::open(dir.path()).expect("open");
            store.put_result("p-1", &doc).expect("result");
            let mut rec = record("p-1", PlanStatus::Active, 1);
            rec.version = 2;
            store.put_correction(&rec, &c1).expect("c1");
            rec.version = 3;
            store.put_correction(&rec, &c2).expect("c2");
        }
        let store = Store::open(dir.path()).expect("reopen");
        assert_eq!(store.corrections("p-1").expect("read"), vec![c1.clone(), c2.clone()]);
        assert_eq!(store.plans().expect("plans")[0].version, 3);
        let expected = c2.apply(&c1.apply(&doc).expect("c1 applies")).expect("c2 applies");
        assert_eq!(store.current("p-1").expect("read"), Some(expected));
        assert_eq!(
            store.result("p-1").expect("read"),
            Some(doc),
            "the computed version is kept"
        );
    }

    #[test]
    fn a_forgotten_plan_leaves_no_row_and_its_neighbours_stay() {
        let dir = tempfile::tempdir().expect("tempdir");
        let store = Store::open(dir.path()).expect("open");
        for id in ["p-1", "p-10"] {
            store.put_plan(&record(id, PlanStatus::Queued, 1)).expect("queued");
            store.put_plan(&record(id, PlanStatus::Ready, 2)).expect("ready");
        }
        store.commit(&[Write::Forget("p-1")]).expect("forget");
        let ids: Vec<String> = store.plans().expect("plans").into_iter().map(|p| p.plan_id).collect();
        assert_eq!(ids, vec!["p-10".to_string()]);
        assert!(store.history("p-1").expect("history").is_empty());
        assert_eq!(
            store.history("p-10").expect("history").len(),
            2,
            "p-10 shares p-1's key prefix"
        );
        assert!(store.corrections("p-1").expect("corrections").is_empty());
    }
}
