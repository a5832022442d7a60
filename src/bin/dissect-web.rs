//! The trainer in a web browser: built for `wasm32-unknown-unknown` by `web/build.sh` (see the README).
//! Natively this binary only says where to look.

#[cfg(target_arch = "wasm32")]
fn main() {
    dissect::web::start();
}

#[cfg(not(target_arch = "wasm32"))]
fn main() {
    eprintln!("dissect-web is the browser build: `web/build.sh`, then `web/serve.sh` (see the README)");
}
