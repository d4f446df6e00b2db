#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| twil_core_fuzz::targets::da(data));
