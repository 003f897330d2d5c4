//! Fuzz target `mcap_replay`: its body is shared with the regression test (`tests/tests/e2e/fuzz_feed.rs`).
#![no_main]

#[allow(dead_code)]
#[path = "../../tests/tests/e2e/fuzz_feed.rs"]
mod feed;

libfuzzer_sys::fuzz_target!(|data: &[u8]| feed::mcap_replay(data));
