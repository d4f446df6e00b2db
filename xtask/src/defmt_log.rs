//! Decode the QEMU firmware's defmt log. Under QEMU the firmware's global defmt logger is
//! `defmt-semihosting`: the frames come out on QEMU's stdout, still binary (interned format
//! strings, rzCOBS framing), and the ELF's `.defmt` table turns them back into text.

use std::io::Read;
use std::path::Path;

use anyhow::{anyhow, Context, Result};
use defmt_decoder::{DecodeError, Table};

/// The defmt table of `elf`.
pub fn table(elf: &Path) -> Result<Table> {
    let bytes = std::fs::read(elf).with_context(|| format!("cannot read {}", elf.display()))?;
    Table::parse(&bytes)
        .map_err(|e| anyhow!("{}: bad defmt table: {e}", elf.display()))?
        .ok_or_else(|| anyhow!("{} has no .defmt section", elf.display()))
}

/// Read defmt frames from `input` until it ends (or `line` returns `false`), decoding each
/// into one line of text for `line`. Damaged frames are skipped (rzCOBS resynchronises at the
/// next frame boundary).
pub fn decode(
    table: &Table,
    mut input: impl Read,
    mut line: impl FnMut(String) -> bool,
) -> Result<()> {
    let mut decoder = table.new_stream_decoder();
    let mut buffer = [0u8; 256];
    loop {
        let n = input.read(&mut buffer).context("reading QEMU's output")?;
        if n == 0 {
            return Ok(());
        }
        decoder.received(&buffer[..n]);
        loop {
            match decoder.decode() {
                Ok(frame) => {
                    if !line(frame.display(false).to_string()) {
                        return Ok(());
                    }
                }
                Err(DecodeError::UnexpectedEof) => break,
                Err(DecodeError::Malformed) => {
                    if !table.encoding().can_recover() {
                        return Err(anyhow!("malformed defmt frame; cannot resynchronise"));
                    }
                }
            }
        }
    }
}
