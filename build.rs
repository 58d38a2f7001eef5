//! Build script: with the `capi` feature, generates the C header `weft.h` from `src/capi/`
//! with cbindgen into `OUT_DIR` (tests/capi.rs checks the committed `include/weft.h` against
//! it). Without the feature it does nothing.

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    #[cfg(feature = "capi")]
    capi_header();
}

#[cfg(feature = "capi")]
fn capi_header() {
    let dir = std::path::PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let out = std::path::PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR")).join("weft.h");
    println!("cargo:rerun-if-changed=src/capi");
    println!("cargo:rerun-if-changed=cbindgen.toml");
    let config = cbindgen::Config::from_file(dir.join("cbindgen.toml")).expect("cbindgen.toml is valid");
    cbindgen::Builder::new()
        .with_config(config)
        // cbindgen follows the `mod` items of mod.rs into world.rs, obstacles.rs and readback.rs;
        // naming those files too declared every function of theirs twice.
        .with_src(dir.join("src/capi/mod.rs"))
        .generate()
        .expect("cbindgen can read src/capi/")
        .write_to_file(out);
}
