//! Builds the runtime cdylib (the FMU's binary) and hands its path to the builder, which embeds
//! it: `cargo build -p fmu-builder` alone would compile fmu-runtime only as an rlib, and an
//! installed builder must not look for a .so in a source tree. The nested cargo uses its own
//! target directory so it never waits on the outer build's lock.

use std::env;
use std::path::PathBuf;
use std::process::Command;

fn main() {
    let manifest_dir = PathBuf::from(env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let runtime = manifest_dir.join("../fmu-runtime");
    let out_dir = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    println!("cargo:rerun-if-changed={}", runtime.join("src").display());
    println!("cargo:rerun-if-changed={}", runtime.join("Cargo.toml").display());
    // the generic FMI layer the runtime links
    let fmi2 = manifest_dir.join("../fmi2");
    println!("cargo:rerun-if-changed={}", fmi2.join("src").display());
    println!("cargo:rerun-if-changed={}", fmi2.join("Cargo.toml").display());
    println!("cargo:rerun-if-env-changed=FMU_RUNTIME_SO");

    let so = if let Ok(prebuilt) = env::var("FMU_RUNTIME_SO") {
        PathBuf::from(prebuilt)
    } else {
        let target_dir = out_dir.join("runtime-target");
        let cargo = env::var("CARGO").unwrap_or_else(|_| "cargo".into());
        let status = Command::new(cargo)
            .args(["build", "--release", "--lib", "--manifest-path"])
            .arg(runtime.join("Cargo.toml"))
            .arg("--target-dir")
            .arg(&target_dir)
            // flags meant for the outer build (coverage, sanitizers, a cross target) must not
            // leak into the FMU binary
            .env_remove("RUSTFLAGS")
            .env_remove("CARGO_ENCODED_RUSTFLAGS")
            .env_remove("CARGO_BUILD_TARGET")
            .env_remove("CARGO_TARGET_DIR")
            .env_remove("CARGO_BUILD_RUSTFLAGS")
            // `cargo clippy` runs the workspace through clippy-driver: the FMU binary is compiled
            // by rustc, and linted where the runtime crate itself is linted
            .env_remove("RUSTC_WORKSPACE_WRAPPER")
            .env_remove("CLIPPY_ARGS")
            .status()
            .expect("cannot run cargo to build fmu-runtime");
        if !status.success() {
            panic!("building the fmu-runtime cdylib failed");
        }
        target_dir.join("release/libfmu_runtime.so")
    };
    let dest = out_dir.join("fmu_runtime.so");
    std::fs::copy(&so, &dest).unwrap_or_else(|e| panic!("cannot copy {}: {e}", so.display()));
}
