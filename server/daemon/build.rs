//! `include_dir!` (src/http/dashboard.rs) cannot tell cargo which files it read: without this, an edit to the
//! page would not rebuild the binary that embeds it.
fn main() {
    println!("cargo:rerun-if-changed=dashboard");
}
