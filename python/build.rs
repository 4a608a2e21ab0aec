//! Empty: it exists so that the `[build-dependencies]` of Cargo.toml, which only align
//! features with the rest of the workspace, are part of the build.

fn main() {}
