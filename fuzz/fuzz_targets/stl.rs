//! STL bytes (binary or ASCII) loaded as a model and rendered.
#![no_main]
libfuzzer_sys::fuzz_target!(|bytes: &[u8]| kage_fuzz::model("m.stl", bytes));
