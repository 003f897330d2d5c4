//! Why the store failed, in the terms callers act on: the disk (or the file-size limit) is full — HTTP 507 —,
//! the data dir is read-only — 503 —, another I/O error, or data the store cannot use.

use std::io;

use redb::StorageError;

/// What kind of failure a store error is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FaultKind {
    /// No space left: `ENOSPC`, a disk quota (`EDQUOT`) or the process's file-size limit (`EFBIG`).
    Full,
    /// The data dir cannot be written: a read-only file system (`EROFS`) or no permission.
    ReadOnly,
    /// Any other I/O error (the store is reopened before its next write).
    Io,
    /// Not an I/O error: data the store cannot use (corrupt, too large, undecodable).
    Data,
}

impl FaultKind {
    /// Its name in logs, metrics and `/readyz`.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Full => "full",
            Self::ReadOnly => "read_only",
            Self::Io => "io",
            Self::Data => "data",
        }
    }

    /// An I/O failure: redb refuses every later operation until the database is reopened.
    pub fn needs_reopen(self) -> bool {
        !matches!(self, Self::Data)
    }

    /// The kind of an OS error.
    pub fn of_io(e: &io::Error) -> Self {
        match e.kind() {
            io::ErrorKind::StorageFull | io::ErrorKind::QuotaExceeded | io::ErrorKind::FileTooLarge => Self::Full,
            io::ErrorKind::ReadOnlyFilesystem | io::ErrorKind::PermissionDenied => Self::ReadOnly,
            _ => Self::Io,
        }
    }
}

/// A store failure: its kind and a message naming what failed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{message}")]
pub struct StoreError {
    /// What kind of failure.
    pub kind: FaultKind,
    /// What failed, for people.
    pub message: String,
}

impl StoreError {
    /// A failure of `kind`.
    pub fn new(kind: FaultKind, message: impl Into<String>) -> Self {
        Self {
            kind,
            message: message.into(),
        }
    }

    /// An OS error, classified.
    pub fn io(e: &io::Error) -> Self {
        let kind = FaultKind::of_io(e);
        let what = match kind {
            FaultKind::Full => "no space left for the store",
            FaultKind::ReadOnly => "the store's data dir is read-only",
            _ => "the store could not be written",
        };
        Self::new(kind, format!("{what} ({e})"))
    }

    fn storage(e: StorageError) -> Self {
        match e {
            StorageError::Io(e) => Self::io(&e),
            StorageError::PreviousIo => Self::new(FaultKind::Io, "an earlier write failed; the store reopens first"),
            other => Self::new(FaultKind::Data, other.to_string()),
        }
    }
}

/// redb's errors, each with a `Storage` variant carrying the I/O error when there is one.
macro_rules! from_redb {
    ($($ty:ident),+ $(,)?) => {
        $(impl From<redb::$ty> for StoreError {
            fn from(e: redb::$ty) -> Self {
                match e {
                    redb::$ty::Storage(s) => Self::storage(s),
                    other => Self::new(FaultKind::Data, other.to_string()),
                }
            }
        })+
    };
}

from_redb!(TransactionError, TableError, CommitError, DatabaseError);

impl From<StorageError> for StoreError {
    fn from(e: StorageError) -> Self {
        Self::storage(e)
    }
}

impl From<redb::Error> for StoreError {
    fn from(e: redb::Error) -> Self {
        match e {
            redb::Error::Io(e) => Self::io(&e),
            redb::Error::PreviousIo => Self::storage(StorageError::PreviousIo),
            other => Self::new(FaultKind::Data, other.to_string()),
        }
    }
}

impl From<serde_json::Error> for StoreError {
    fn from(e: serde_json::Error) -> Self {
        Self::new(FaultKind::Data, format!("JSON: {e}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn os_errors_are_classified_by_what_an_operator_does_about_them() {
        let os = |code| FaultKind::of_io(&io::Error::from_raw_os_error(code));
        // Linux errno values.
        assert_eq!(os(28), FaultKind::Full, "ENOSPC");
        assert_eq!(os(122), FaultKind::Full, "EDQUOT");
        assert_eq!(os(27), FaultKind::Full, "EFBIG (RLIMIT_FSIZE)");
        assert_eq!(os(30), FaultKind::ReadOnly, "EROFS");
        assert_eq!(os(13), FaultKind::ReadOnly, "EACCES");
        assert_eq!(os(5), FaultKind::Io, "EIO");
        let e = StoreError::from(redb::CommitError::Storage(StorageError::Io(
            io::Error::from_raw_os_error(28),
        )));
        assert_eq!(e.kind, FaultKind::Full);
        assert!(e.message.contains("no space left"), "{e}");
        assert_eq!(
            StoreError::from(redb::TransactionError::Storage(StorageError::PreviousIo)).kind,
            FaultKind::Io
        );
        assert!(!FaultKind::Data.needs_reopen() && FaultKind::Full.needs_reopen());
    }
}
