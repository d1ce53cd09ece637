//! The extension module's link arguments: on macOS a shared library may not leave symbols
//! undefined unless told so, and the module takes Python's from the interpreter that loads
//! it (what `pyo3_build_config::add_extension_module_link_args` emits, without building that
//! crate for one line). Elsewhere nothing is needed.

fn main() {
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("macos") {
        println!("cargo:rustc-cdylib-link-arg=-undefined");
        println!("cargo:rustc-cdylib-link-arg=dynamic_lookup");
    }
}
