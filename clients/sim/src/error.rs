//! The simulator library's errors.

/// What went wrong.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// A field of the input is wrong; the message names it.
    #[error("{field}: {message}")]
    BadInput {
        /// The field.
        field: String,
        /// What is wrong with it.
        message: String,
    },
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// Why.
        source: std::io::Error,
    },
    /// The map could not be loaded.
    #[error("map: {0}")]
    Map(String),
    /// The daemon or Zenoh failed.
    #[error("fleet: {0}")]
    Fleet(String),
}

/// A bad-input error naming `field`.
pub fn bad(field: &str, message: impl Into<String>) -> SimError {
    SimError::BadInput {
        field: field.to_owned(),
        message: message.into(),
    }
}
