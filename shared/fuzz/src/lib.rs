//! The fuzz targets' bodies, one function per decoder or parser (see `targets`). The cargo-fuzz
//! binaries in `fuzz_targets/` call them; the stable test `shared/tests/fuzz_corpus.rs` includes
//! the same file by path and replays the checked-in corpus through them.
pub mod targets;
