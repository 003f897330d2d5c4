//! Unit tests of the correction stage.
