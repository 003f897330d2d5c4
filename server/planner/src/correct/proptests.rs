//! Property tests of the correction stage.
