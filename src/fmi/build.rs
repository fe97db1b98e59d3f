//! Compiles the FMI 2 logger shim (logger.c): the callback FMI 2 asks for is printf-style variadic, which stable
//! Rust cannot define.
fn main() {
    println!("cargo:rerun-if-changed=logger.c");
    cc::Build::new().file("logger.c").warnings(true).compile("silrig_fmi_logger");
}
