//! Parameter values kept in the MCU's flash: a map from a stable 32-bit id to an `f32`, written
//! with `sequential-storage`'s `map` over any `embedded-storage` `NorFlash`, safe against a
//! power cut at any moment (issue 25, part 2: "parameters on the device").
//!
//! Seed 003 compiles every constant of the robot in (`twlparam.h`); a robot user expects what
//! ArduPilot gives: values set on the device, kept across resets, and a device that starts on
//! its defaults (and says so) when the store cannot be trusted.
//!
//! ## Format
//!
//! Each record is one `sequential-storage` map item: key = the parameter's [`ParamId`] (the
//! 32-bit FNV-1a hash of its name, so adding or renaming one parameter never moves another),
//! value = the `f32`'s bits, both little-endian, 8 bytes of data behind the crate's 8-byte
//! header (data length, a CRC-16 of the length, a CRC-32 of the data). The id 0
//! ([`ParamId::FORMAT`]) holds the format word [`FORMAT_WORD`]: magic `0x5457` ("TW") in the
//! high half, [`FORMAT_VERSION`] in the low half. A newer record of an id supersedes the older
//! ones; when a page fills, the crate copies the live records to the next page and erases the
//! oldest one (at least two pages; the board gives it two 128 KiB sectors).
//!
//! ## What loading finds ([`StoreStatus`])
//!
//! - `Ok`: the format word of this version; every known id's newest value is returned.
//! - `Empty`: no record at all (a new chip, or after [`ParamStore::erase`]): defaults.
//! - `OldVersion`: the magic with another version: defaults (nothing is converted).
//! - `Corrupt`: anything else (records without a format word, a foreign word, damage the crate
//!   could not repair, a flash read error): defaults.
//!
//! Ids the caller does not know are skipped and counted ([`LoadReport::unknown`]): a store
//! written by a newer firmware still loads the values this one knows.
//!
//! ## Power loss
//!
//! `sequential-storage` writes an item's data before it makes the item valid, and checks the
//! CRCs when reading: a record cut short is ignored, so the previous record of that id stays
//! the newest. A cut during a page copy or erase is repaired by the crate on the next access.
//! The first save on a store that is not `Ok` erases it and writes the format word first, so
//! a cut there leaves `Empty` (defaults, as before the save). The tests cut every write of a
//! long series of saves after each byte and each erase (`cargo test --release -p twil-core
//! params_store::tests::power_loss`): the store then loads the old or the new value, never
//! another, and the next save works (numbers in docs/firmware.md).
//!
//! ## Blocking
//!
//! `sequential-storage` 8 is `async` (`embedded-storage-async`). The chip's flash is blocking
//! (the core stalls while it programs), so [`BlockingFlash`] presents a blocking `NorFlash` as
//! an async one whose futures are ready at the first poll, and every operation here polls its
//! future once ([`block_on`]): no executor, no spinning; an async flash that is not ready is
//! an error ([`StoreError::Pending`]).

use core::fmt;
use core::future::Future;
use core::ops::Range;
use core::task::{Context, Poll, Waker};

use embedded_storage::nor_flash::{NorFlash, ReadNorFlash};
use sequential_storage::cache::{Cache, Uncached};
use sequential_storage::map::{MapConfig, MapStorage};

pub mod ram_flash;
pub mod robot;

#[cfg(test)]
mod tests;

/// The format word's high half: "TW".
pub const FORMAT_MAGIC: u32 = 0x5457_0000;
/// The version of the record format; a store of another version loads as
/// [`StoreStatus::OldVersion`].
pub const FORMAT_VERSION: u16 = 1;
/// The value of the record [`ParamId::FORMAT`] (the bits of a `u32`, not of an `f32`).
pub const FORMAT_WORD: u32 = FORMAT_MAGIC | FORMAT_VERSION as u32;
/// Bytes of the buffer the crate reads and writes one item through: key and value (8 bytes)
/// rounded up to the largest flash word `sequential-storage` supports (32 bytes).
pub const ITEM_BUFFER_BYTES: usize = 32;

/// A parameter's stable id: the 32-bit FNV-1a hash of its name ([`ParamId::of_name`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ParamId(pub u32);

impl ParamId {
    /// The record of the format word: no parameter may have it.
    pub const FORMAT: ParamId = ParamId(0);

    /// The id of the parameter `name`: 32-bit FNV-1a of its bytes (offset basis 0x811C_9DC5,
    /// prime 0x0100_0193).
    ///
    /// ```
    /// use twil_core::params_store::ParamId;
    /// assert_eq!(ParamId::of_name(""), ParamId(0x811C_9DC5));
    /// assert_eq!(ParamId::of_name("a"), ParamId(0xE40C_292C));
    /// ```
    pub const fn of_name(name: &str) -> ParamId {
        let bytes = name.as_bytes();
        let mut hash: u32 = 0x811C_9DC5;
        let mut i = 0;
        while i < bytes.len() {
            hash ^= bytes[i] as u32;
            hash = hash.wrapping_mul(0x0100_0193);
            i += 1;
        }
        ParamId(hash)
    }
}

/// What [`ParamStore::load`] found (see the module's doc). On the link in
/// [`ParamEntry::store`](crate::link::ParamEntry::store), variant index = the order here.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StoreStatus {
    /// This format; the stored values were returned.
    Ok,
    /// Nothing stored: defaults.
    Empty,
    /// Unreadable, damaged or foreign: defaults.
    Corrupt,
    /// Written by another version of the format: defaults.
    OldVersion,
}

impl fmt::Display for StoreStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            StoreStatus::Ok => "ok",
            StoreStatus::Empty => "empty",
            StoreStatus::Corrupt => "corrupt",
            StoreStatus::OldVersion => "old version",
        })
    }
}

/// What one [`ParamStore::load`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LoadReport {
    /// What the store holds; anything but `Ok` returned no value.
    pub status: StoreStatus,
    /// Known ids given a stored value.
    pub found: u16,
    /// Records of ids the caller did not list (skipped).
    pub unknown: u32,
    /// Records read, superseded ones and the format word included.
    pub records: u32,
    /// The format word read (`None`: none).
    pub format_word: Option<u32>,
}

/// Why a store operation failed. The flash holds what it held before, or a cut-short record
/// that the next load ignores.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StoreError {
    /// The flash range is unusable: it must start and end on erase-page boundaries and hold
    /// at least two pages.
    BadRange {
        /// First byte, flash offset.
        start: u32,
        /// One past the last byte, flash offset.
        end: u32,
    },
    /// The id is [`ParamId::FORMAT`], which no parameter may use.
    ReservedId,
    /// The value is NaN or infinite.
    NotFinite {
        /// The parameter.
        id: ParamId,
        /// Its value.
        value: f32,
    },
    /// The flash driver reported an error (erase or program).
    Flash,
    /// The live records do not fit in one page.
    Full,
    /// The crate found damage that its repair did not fix: [`ParamStore::erase`] recovers.
    Corrupt,
    /// The flash's future was not ready at once: this store drives blocking flashes only.
    Pending,
    /// Another `sequential-storage` error (its own bug, a buffer size): a defect here.
    Internal,
}

impl fmt::Display for StoreError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StoreError::BadRange { start, end } => write!(
                f,
                "parameter store range {start:#x}..{end:#x} is not at least two whole erase pages"
            ),
            StoreError::ReservedId => write!(f, "parameter id 0 is the store's format record"),
            StoreError::NotFinite { id, value } => {
                write!(f, "parameter {:#010x} = {value} is not finite", id.0)
            }
            StoreError::Flash => write!(f, "parameter store: the flash reported an error"),
            StoreError::Full => write!(f, "parameter store: the live values fill a page"),
            StoreError::Corrupt => write!(f, "parameter store: damaged beyond repair (erase it)"),
            StoreError::Pending => write!(f, "parameter store: the flash did not complete at once"),
            StoreError::Internal => write!(f, "parameter store: internal error"),
        }
    }
}

impl core::error::Error for StoreError {}

impl<E> From<sequential_storage::Error<E>> for StoreError {
    fn from(e: sequential_storage::Error<E>) -> Self {
        match e {
            sequential_storage::Error::Storage { .. } => StoreError::Flash,
            sequential_storage::Error::FullStorage => StoreError::Full,
            sequential_storage::Error::Corrupted { .. } => StoreError::Corrupt,
            _ => StoreError::Internal,
        }
    }
}

/// A blocking `embedded-storage` flash seen as an `embedded-storage-async` one: each operation
/// runs to its end inside the first poll.
pub struct BlockingFlash<F>(pub F);

impl<F: embedded_storage::nor_flash::ErrorType> embedded_storage_async::nor_flash::ErrorType
    for BlockingFlash<F>
{
    type Error = F::Error;
}

impl<F: ReadNorFlash> embedded_storage_async::nor_flash::ReadNorFlash for BlockingFlash<F> {
    const READ_SIZE: usize = F::READ_SIZE;

    async fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        self.0.read(offset, bytes)
    }

    fn capacity(&self) -> usize {
        self.0.capacity()
    }
}

impl<F: NorFlash> embedded_storage_async::nor_flash::NorFlash for BlockingFlash<F> {
    const WRITE_SIZE: usize = F::WRITE_SIZE;
    const ERASE_SIZE: usize = F::ERASE_SIZE;

    async fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        self.0.erase(from, to)
    }

    async fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        self.0.write(offset, bytes)
    }
}

/// Poll `future` once: its value, or [`StoreError::Pending`] if it was not ready (bounded
/// work: never a second poll, never a wait).
pub fn block_on<T>(future: impl Future<Output = T>) -> Result<T, StoreError> {
    let mut future = core::pin::pin!(future);
    let mut cx = Context::from_waker(Waker::noop());
    match future.as_mut().poll(&mut cx) {
        Poll::Ready(value) => Ok(value),
        Poll::Pending => Err(StoreError::Pending),
    }
}

/// No cache: every read goes to the flash (memory-mapped on the chip, so cheap), and no RAM
/// is spent on page states or key pointers.
type NoCache = Cache<Uncached, Uncached, Uncached, u32>;

/// Parameter values in a range of flash (see the module's doc).
pub struct ParamStore<F: NorFlash> {
    map: MapStorage<u32, BlockingFlash<F>, NoCache>,
    buffer: [u8; ITEM_BUFFER_BYTES],
    /// What the last load found, kept up to date by save and erase (`None`: not known, e.g.
    /// after a failed operation).
    status: Option<StoreStatus>,
}

impl<F: NorFlash> ParamStore<F> {
    /// A store in `range` of `flash` (offsets as the flash driver counts them). Nothing is
    /// read yet.
    pub fn new(flash: F, range: Range<u32>) -> Result<Self, StoreError> {
        let bad = StoreError::BadRange {
            start: range.start,
            end: range.end,
        };
        let config = MapConfig::try_new(range).map_err(|_| bad)?;
        Ok(Self {
            map: MapStorage::new(BlockingFlash(flash), config, Cache::new_uncached()),
            buffer: [0; ITEM_BUFFER_BYTES],
            status: None,
        })
    }

    /// The flash back (nothing is kept in RAM that the flash does not hold).
    pub fn into_flash(self) -> F {
        self.map.destroy().0 .0
    }

    /// What the last load found (`None` before one, or after a failed save or erase).
    pub fn status(&self) -> Option<StoreStatus> {
        self.status
    }

    /// Read every record: `values[i]` becomes the newest stored value of `ids[i]` (`None`: not
    /// stored). Anything but [`StoreStatus::Ok`] leaves every value `None` (defaults). Ids not
    /// in `ids` are skipped; `values` shorter than `ids` drops the values past its end. Work:
    /// one pass over the records (`ids.len()` compares each), a second after a repair; a
    /// repair may erase a page (on the chip: seconds, see docs/firmware.md).
    pub fn load(&mut self, ids: &[ParamId], values: &mut [Option<f32>]) -> LoadReport {
        let (mut scanned, mut report) = self.scan(ids, values);
        if scanned == Err(StoreError::Corrupt) {
            // sequential-storage 8.0.2's `fetch_all_items` returns the damage of a page whose
            // erase a power loss cut (start erased, end still marked) without repairing it;
            // `fetch_item` repairs it (erases that page again; the live records are in the
            // other). Then read again, once. Found by the power-loss test.
            let _ = block_on(
                self.map
                    .fetch_item::<u32>(&mut self.buffer, &ParamId::FORMAT.0),
            );
            (scanned, report) = self.scan(ids, values);
        }
        report.status = match (scanned, report.format_word) {
            (Ok(()), Some(FORMAT_WORD)) => StoreStatus::Ok,
            (Ok(()), None) if report.records == 0 => StoreStatus::Empty,
            (Ok(()), Some(word)) if word & 0xFFFF_0000 == FORMAT_MAGIC && word != FORMAT_WORD => {
                StoreStatus::OldVersion
            }
            _ => StoreStatus::Corrupt,
        };
        if report.status == StoreStatus::Ok {
            report.found = values.iter().filter(|v| v.is_some()).count() as u16;
        } else {
            values.iter_mut().for_each(|v| *v = None);
        }
        self.status = Some(report.status);
        report
    }

    /// One pass over the records (see [`ParamStore::load`]): what it found, and how it ended.
    fn scan(
        &mut self,
        ids: &[ParamId],
        values: &mut [Option<f32>],
    ) -> (Result<(), StoreError>, LoadReport) {
        values.iter_mut().for_each(|v| *v = None);
        let mut report = LoadReport {
            status: StoreStatus::Corrupt,
            found: 0,
            unknown: 0,
            records: 0,
            format_word: None,
        };
        let scanned = block_on(scan(
            &mut self.map,
            &mut self.buffer,
            ids,
            values,
            &mut report,
        ));
        (scanned.and_then(|r| r), report)
    }

    /// Store `value` as the newest value of `id` (nothing is written when it already is). On a
    /// store that is not [`StoreStatus::Ok`] (loaded or, if not known, checked first), this
    /// erases the range and writes the format word first: its old records were not in use.
    ///
    /// The value is not checked against any limit here: the caller validates it.
    pub fn save(&mut self, id: ParamId, value: f32) -> Result<(), StoreError> {
        if id == ParamId::FORMAT {
            return Err(StoreError::ReservedId);
        }
        if !value.is_finite() {
            return Err(StoreError::NotFinite { id, value });
        }
        let status = match self.status {
            Some(status) => status,
            None => self.load(&[], &mut []).status,
        };
        let result = self.save_in(status, id, value);
        if result.is_err() {
            self.status = None;
        }
        result
    }

    fn save_in(&mut self, status: StoreStatus, id: ParamId, value: f32) -> Result<(), StoreError> {
        if status != StoreStatus::Ok {
            self.format()?;
        }
        let bits = value.to_bits();
        let stored = block_on(self.map.fetch_item::<u32>(&mut self.buffer, &id.0))??;
        if stored != Some(bits) {
            block_on(self.map.store_item(&mut self.buffer, &id.0, &bits))??;
        }
        Ok(())
    }

    /// Erase the whole range and write the format word: the store loads `Ok` with no value,
    /// and the next [`ParamStore::save`] needs no erase. The board's boot does this to a
    /// store that is not `Ok`, before its watchdog starts (firmware/src/params.rs).
    pub fn format(&mut self) -> Result<(), StoreError> {
        self.status = None;
        block_on(self.map.erase_all())??;
        self.status = Some(StoreStatus::Empty);
        block_on(
            self.map
                .store_item(&mut self.buffer, &ParamId::FORMAT.0, &FORMAT_WORD),
        )??;
        self.status = Some(StoreStatus::Ok);
        Ok(())
    }

    /// Erase the whole range: every value back to its default at the next load.
    pub fn erase(&mut self) -> Result<(), StoreError> {
        self.status = None;
        block_on(self.map.erase_all())??;
        self.status = Some(StoreStatus::Empty);
        Ok(())
    }
}

/// One pass over every record (see [`ParamStore::load`]).
async fn scan<F: NorFlash>(
    map: &mut MapStorage<u32, BlockingFlash<F>, NoCache>,
    buffer: &mut [u8; ITEM_BUFFER_BYTES],
    ids: &[ParamId],
    values: &mut [Option<f32>],
    report: &mut LoadReport,
) -> Result<(), StoreError> {
    let mut records = map.fetch_all_items(buffer).await?;
    while let Some((key, bits)) = records.next::<u32>(buffer).await? {
        report.records += 1;
        if key == ParamId::FORMAT.0 {
            report.format_word = Some(bits);
            continue;
        }
        match ids.iter().position(|id| id.0 == key) {
            Some(i) => {
                if let Some(slot) = values.get_mut(i) {
                    *slot = Some(f32::from_bits(bits));
                }
            }
            None => report.unknown += 1,
        }
    }
    Ok(())
}
