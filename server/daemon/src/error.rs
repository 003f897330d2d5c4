//! The daemon library's one error type. Binaries (`main.rs`) wrap it with `anyhow` for their own messages.

use std::fmt::Display;

use shift_engine::EngineError;
use shift_planner::PlannerError;

/// What can go wrong in the daemon's adapters: files, the store, Zenoh, recordings, configuration.
#[derive(Debug, thiserror::Error)]
pub enum DaemonError {
    /// A file or socket operation failed.
    #[error("{context}: {source}")]
    Io {
        /// What was being done (names the path).
        context: String,
        /// The OS error.
        #[source]
        source: std::io::Error,
    },
    /// The configuration is not usable; the message names the key.
    #[error("configuration: {0}")]
    Config(String),
    /// The Zenoh session or one of its declarations failed.
    #[error("zenoh: {0}")]
    Zenoh(String),
    /// The store failed (redb), classified: full, read-only, other I/O, unusable data.
    #[error("store: {0}")]
    Store(#[from] crate::store::fault::StoreError),
    /// The engine refused.
    #[error(transparent)]
    Engine(#[from] EngineError),
    /// The engine loop did not carry an event out.
    #[error(transparent)]
    Loop(#[from] crate::engine_loop::handle::LoopError),
    /// The planner refused or failed.
    #[error(transparent)]
    Planner(#[from] PlannerError),
    /// An MCAP recording could not be written or read.
    #[error("recording: {0}")]
    Recording(String),
    /// JSON that does not parse or cannot be written.
    #[error("JSON: {0}")]
    Json(#[from] serde_json::Error),
    /// Anything else, with what was being done.
    #[error("{0}")]
    Other(String),
}

impl DaemonError {
    /// A configuration error.
    pub fn config(msg: impl Into<String>) -> Self {
        Self::Config(msg.into())
    }

    /// Any other error.
    pub fn msg(msg: impl Into<String>) -> Self {
        Self::Other(msg.into())
    }
}

impl From<std::io::Error> for DaemonError {
    fn from(source: std::io::Error) -> Self {
        Self::Io {
            context: "I/O".into(),
            source,
        }
    }
}

/// Foreign errors that convert into one variant with their message.
macro_rules! from_display {
    ($variant:ident: $($ty:ty),+ $(,)?) => {
        $(impl From<$ty> for DaemonError {
            fn from(e: $ty) -> Self {
                Self::$variant(e.to_string())
            }
        })+
    };
}

/// redb's errors become a classified [`crate::store::fault::StoreError`].
macro_rules! from_store {
    ($($ty:ty),+ $(,)?) => {
        $(impl From<$ty> for DaemonError {
            fn from(e: $ty) -> Self {
                Self::Store(e.into())
            }
        })+
    };
}

from_store!(
    redb::Error,
    redb::DatabaseError,
    redb::TransactionError,
    redb::TableError,
    redb::CommitError,
    redb::StorageError
);
from_display!(Config: toml::de::Error);
from_display!(Recording: mcap::McapError);
from_display!(Other: tokio::task::JoinError, image::ImageError);

/// The daemon library's result.
pub type Result<T, E = DaemonError> = std::result::Result<T, E>;

/// Adds what was being done to an error (the daemon's counterpart of `anyhow::Context`).
pub trait Context<T> {
    /// Wraps the error with `context`.
    fn context(self, context: impl Display) -> Result<T>;
    /// Wraps the error with the context `f` gives (only computed on error).
    fn with_context<C: Display>(self, f: impl FnOnce() -> C) -> Result<T>;
}

impl<T, E: Display> Context<T> for std::result::Result<T, E> {
    fn context(self, context: impl Display) -> Result<T> {
        self.map_err(|e| DaemonError::Other(format!("{context}: {e}")))
    }

    fn with_context<C: Display>(self, f: impl FnOnce() -> C) -> Result<T> {
        self.map_err(|e| DaemonError::Other(format!("{}: {e}", f())))
    }
}

impl<T> Context<T> for Option<T> {
    fn context(self, context: impl Display) -> Result<T> {
        self.ok_or_else(|| DaemonError::Other(context.to_string()))
    }

    fn with_context<C: Display>(self, f: impl FnOnce() -> C) -> Result<T> {
        self.ok_or_else(|| DaemonError::Other(f().to_string()))
    }
}

/// Returns early with [`DaemonError::Other`] built like `format!`.
#[macro_export]
macro_rules! bail {
    ($($arg:tt)*) => {
        return Err($crate::error::DaemonError::Other(format!($($arg)*)))
    };
}

/// [`DaemonError::Other`] built like `format!`.
#[macro_export]
macro_rules! err {
    ($($arg:tt)*) => {
        $crate::error::DaemonError::Other(format!($($arg)*))
    };
}
