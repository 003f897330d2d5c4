//! SHIFT wire types.
