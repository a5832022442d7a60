//! The `dissect` command line.
fn main() {
    println!("dissect: the trainer is being built; run `cargo test` to check the engine.");
}
