//! The parameter store against a RAM flash: round trip, statuses, damage, and a power cut at
//! every byte programmed and every page erased of a long series of saves.

extern crate std;

use super::ram_flash::{RamFlash, RamFlashError};
use super::*;
use embedded_storage::nor_flash::{ErrorType, NorFlashError, NorFlashErrorKind};
use std::boxed::Box;
use std::vec::Vec;
use std::{format, println};

/// Pages of the test flash, bytes: small, so that a series of saves fills pages and makes the
/// crate copy records and erase pages often (63 records a page).
const PAGE: usize = 1024;
/// The test flash: two pages, as the board's two sectors.
type Ram = RamFlash<2048, PAGE>;
const RANGE: Range<u32> = 0..2048;

fn id(name: &str) -> ParamId {
    ParamId::of_name(name)
}

fn store(flash: Ram) -> ParamStore<Ram> {
    ParamStore::new(flash, RANGE).unwrap()
}

/// Write records with the crate directly (formats this store does not write).
fn raw_records(flash: Ram, records: &[(u32, u32)]) -> Ram {
    let config = MapConfig::try_new(RANGE).unwrap();
    let mut map: MapStorage<u32, _, NoCache> =
        MapStorage::new(BlockingFlash(flash), config, Cache::new_uncached());
    let mut buffer = [0; ITEM_BUFFER_BYTES];
    for (key, value) in records {
        block_on(map.store_item(&mut buffer, key, value))
            .unwrap()
            .unwrap();
    }
    map.destroy().0 .0
}

#[test]
fn values_round_trip_and_unknown_ids_are_skipped() {
    let mut s = store(Ram::ERASED);
    let (a, b, c) = (
        id("wheel_radius_m"),
        id("half_axle_m"),
        id("not_known_here"),
    );
    let mut values = [None; 2];
    assert_eq!(s.load(&[a, b], &mut values).status, StoreStatus::Empty);
    s.save(a, 0.05).unwrap();
    s.save(b, 0.2).unwrap();
    s.save(a, 0.06).unwrap();
    s.save(c, 7.0).unwrap();
    // A new store on the same flash: what a reset sees.
    let mut s = store(s.into_flash());
    let report = s.load(&[a, b], &mut values);
    assert_eq!(values, [Some(0.06), Some(0.2)]);
    assert_eq!(report.status, StoreStatus::Ok);
    assert_eq!(report.found, 2);
    assert_eq!(report.unknown, 1);
    assert_eq!(report.records, 5); // format word, a twice, b, c
    assert_eq!(report.format_word, Some(FORMAT_WORD));
    // Fewer slots than ids: the rest are dropped, nothing panics.
    let mut one = [None; 1];
    s.load(&[a, b], &mut one);
    assert_eq!(one, [Some(0.06)]);
}

#[test]
fn saving_the_stored_value_writes_nothing() {
    let mut s = store(Ram::ERASED);
    s.save(id("x"), 1.5).unwrap();
    let flash = s.into_flash();
    let before = *flash.as_bytes();
    let mut s = store(flash);
    s.save(id("x"), 1.5).unwrap();
    assert_eq!(*s.into_flash().as_bytes(), before);
}

#[test]
fn refuses_the_format_id_and_values_that_are_not_finite() {
    let mut s = store(Ram::ERASED);
    assert_eq!(s.save(ParamId::FORMAT, 1.0), Err(StoreError::ReservedId));
    let e = s.save(id("x"), f32::NAN).unwrap_err();
    assert!(matches!(e, StoreError::NotFinite { .. }), "{e:?}");
    assert!(s.save(id("x"), f32::INFINITY).is_err());
    // Nothing was written.
    assert!(s.into_flash().as_bytes().iter().all(|&b| b == 0xFF));
}

#[test]
fn another_format_version_loads_defaults_and_the_next_save_starts_afresh() {
    let a = id("a");
    let old = raw_records(Ram::ERASED, &[(0, FORMAT_MAGIC), (a.0, 2.0f32.to_bits())]);
    let mut s = store(old);
    let mut values = [None; 1];
    let report = s.load(&[a], &mut values);
    assert_eq!(report.status, StoreStatus::OldVersion);
    assert_eq!(values, [None]);
    assert_eq!(report.format_word, Some(FORMAT_MAGIC));
    s.save(id("b"), 1.0).unwrap();
    let mut s = store(s.into_flash());
    let report = s.load(&[a, id("b")], &mut [None; 2]);
    assert_eq!(report.status, StoreStatus::Ok);
    assert_eq!(report.records, 2, "the old records were erased");
}

#[test]
fn records_without_this_format_word_load_as_corrupt() {
    let a = id("a");
    for records in [
        &[(a.0, 1.0f32.to_bits())][..],
        &[(0, 0x1234_5678), (a.0, 1.0f32.to_bits())][..],
    ] {
        let mut s = store(raw_records(Ram::ERASED, records));
        let mut values = [None; 1];
        assert_eq!(s.load(&[a], &mut values).status, StoreStatus::Corrupt);
        assert_eq!(values, [None]);
    }
}

#[test]
fn a_damaged_record_is_ignored_and_the_one_before_it_loads() {
    let a = id("a");
    let mut s = store(Ram::ERASED);
    s.save(a, 1.0).unwrap();
    s.save(a, 2.0).unwrap();
    let mut flash = s.into_flash();
    // The last record's data is its last 8 written bytes; flip one bit of its value.
    let bytes = flash.as_bytes_mut();
    let end = bytes[..PAGE].iter().rposition(|&b| b != 0xFF).unwrap();
    bytes[end] ^= 0x01;
    let mut s = store(flash);
    let mut values = [None; 1];
    let report = s.load(&[a], &mut values);
    assert_eq!((report.status, values), (StoreStatus::Ok, [Some(1.0)]));
}

#[test]
fn format_leaves_an_ok_store_without_values() {
    let mut s = store(Ram::ERASED);
    s.save(id("a"), 3.0).unwrap();
    s.format().unwrap();
    let mut values = [None; 1];
    let load = s.load(&[id("a")], &mut values);
    assert_eq!((load.status, load.records), (StoreStatus::Ok, 1));
    assert_eq!(values, [None]);
}

#[test]
fn erase_brings_back_the_defaults() {
    let mut s = store(Ram::ERASED);
    s.save(id("a"), 3.0).unwrap();
    s.erase().unwrap();
    assert_eq!(s.status(), Some(StoreStatus::Empty));
    let mut values = [None; 1];
    assert_eq!(s.load(&[id("a")], &mut values).status, StoreStatus::Empty);
    assert_eq!(values, [None]);
}

#[test]
fn any_bytes_in_flash_load_without_panic_and_a_save_recovers() {
    // A xorshift generator: the same "random" flash contents on every run.
    let mut state = 0x2545_F491u32;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        state
    };
    for round in 0..200 {
        let mut flash = Ram::ERASED;
        // Some rounds damage only part of a valid store, the others fill everything.
        if round % 2 == 0 {
            let mut s = store(flash);
            for k in 0..20 {
                s.save(id("a"), k as f32).unwrap();
            }
            flash = s.into_flash();
            let start = (next() as usize) % 2048;
            let len = 1 + (next() as usize) % 64;
            for b in flash.as_bytes_mut()[start..].iter_mut().take(len) {
                *b = next() as u8;
            }
        } else {
            for b in flash.as_bytes_mut().iter_mut() {
                *b = next() as u8;
            }
        }
        let mut s = store(flash);
        let mut values = [None; 1];
        let report = s.load(&[id("a")], &mut values);
        if report.status == StoreStatus::Ok {
            // Whatever survived is a value that was saved.
            assert!(values[0].is_none_or(|v| (0.0..20.0).contains(&v) && v.fract() == 0.0));
        } else {
            assert_eq!(values, [None]);
        }
        // A save may meet damage the crate cannot repair: then erase recovers.
        if s.save(id("a"), 42.0).is_err() {
            s.erase().unwrap();
            s.save(id("a"), 42.0).unwrap();
        }
        let mut s = store(s.into_flash());
        assert_eq!(s.load(&[id("a")], &mut values).status, StoreStatus::Ok);
        assert_eq!(values, [Some(42.0)], "round {round}");
    }
}

#[test]
fn block_on_a_future_that_is_not_ready_is_an_error() {
    assert_eq!(
        block_on(core::future::pending::<()>()),
        Err(StoreError::Pending)
    );
    assert_eq!(block_on(async { 7 }), Ok(7));
}

#[test]
fn the_board_layout_fills_a_sector_and_moves_on() {
    // The board: two sectors of 128 KiB (sectors 10 and 11).
    type Board = RamFlash<{ 256 * 1024 }, { 128 * 1024 }>;
    let mut board = Box::new(Board::ERASED);
    let mut s = ParamStore::new(&mut *board, 0..256 * 1024).unwrap();
    let (a, b) = (id("a"), id("b"));
    s.save(b, -1.0).unwrap();
    // 8 190 records fit in a sector (16 bytes each behind two 1-byte page markers): 9 000
    // saves go past it, so the crate copies the live records to the other sector.
    for k in 0..9_000 {
        s.save(a, k as f32).unwrap();
    }
    // The live records moved to the second sector and the first was erased.
    let flash = s.into_flash();
    assert!(flash.as_bytes()[0] == 0xFF && flash.as_bytes()[128 * 1024] != 0xFF);
    // A reset: a new store on the same flash.
    let mut s = ParamStore::new(&mut *board, 0..256 * 1024).unwrap();
    let mut values = [None; 2];
    let report = s.load(&[a, b], &mut values);
    assert_eq!(report.status, StoreStatus::Ok);
    assert_eq!(values, [Some(8_999.0), Some(-1.0)]);
    assert!(report.records < 9_000, "{} records", report.records);
}

// --- Power loss ----------------------------------------------------------------------------

/// What the cut flash counts: one operation per byte programmed and per page erased.
#[derive(Clone, Copy, Debug, PartialEq)]
enum CutError {
    /// The power went (this and every later operation fail until [`CutFlash::power_back`]).
    Cut,
    Ram(RamFlashError),
}

impl NorFlashError for CutError {
    fn kind(&self) -> NorFlashErrorKind {
        NorFlashErrorKind::Other
    }
}

/// A RAM flash whose power goes at operation `cut_at` (counted from 0): the operations before
/// it complete; that byte is half programmed (only some of its 0 bits are), that page half
/// erased (its first half); nothing after it happens.
#[derive(Clone)]
struct CutFlash {
    ram: Ram,
    ops: u32,
    cut_at: Option<u32>,
    dead: bool,
}

impl CutFlash {
    fn new() -> Self {
        Self {
            ram: Ram::ERASED,
            ops: 0,
            cut_at: None,
            dead: false,
        }
    }

    /// Power comes back: the flash works again, with what it holds; counting starts over.
    fn power_back(mut self) -> Self {
        self.dead = false;
        self.cut_at = None;
        self.ops = 0;
        self
    }

    /// Count one operation: `false` if the power goes now.
    fn step(&mut self) -> Result<bool, CutError> {
        if self.dead {
            return Err(CutError::Cut);
        }
        if self.cut_at == Some(self.ops) {
            self.dead = true;
            return Ok(false);
        }
        self.ops += 1;
        Ok(true)
    }
}

impl ErrorType for CutFlash {
    type Error = CutError;
}

impl ReadNorFlash for CutFlash {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), CutError> {
        if self.dead {
            return Err(CutError::Cut);
        }
        self.ram.read(offset, bytes).map_err(CutError::Ram)
    }

    fn capacity(&self) -> usize {
        self.ram.capacity()
    }
}

impl NorFlash for CutFlash {
    const WRITE_SIZE: usize = 1;
    const ERASE_SIZE: usize = PAGE;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), CutError> {
        let mut page = from;
        while page < to {
            if !self.step()? {
                let half = page as usize..page as usize + PAGE / 2;
                self.ram.as_bytes_mut()[half].fill(0xFF);
                return Err(CutError::Cut);
            }
            self.ram
                .erase(page, page + PAGE as u32)
                .map_err(CutError::Ram)?;
            page += PAGE as u32;
        }
        Ok(())
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), CutError> {
        for (i, &b) in bytes.iter().enumerate() {
            let at = offset + i as u32;
            if !self.step()? {
                // Programming clears bits: a cut one has cleared only some of them.
                self.ram.as_bytes_mut()[at as usize] &= b | 0xA5;
                return Err(CutError::Cut);
            }
            self.ram.write(at, &[b]).map_err(CutError::Ram)?;
        }
        Ok(())
    }
}

/// The saves of the power-loss series: (parameter, value), ids cycling unevenly so that the
/// crate's page copies carry several live records.
fn series(count: usize) -> Vec<(usize, f32)> {
    (0..count)
        .map(|k| ((k * 7 + k / 5) % 4, k as f32 * 0.25 + 0.125))
        .collect()
}

/// Cut the power at every operation of every save of the series; after each cut the store
/// must hold, for every parameter, the value before the save or (the one saved) the new one,
/// load as `Ok` once anything was ever saved, and take the next save; a second cut during the
/// repair that the first one may call for must keep the same values. Returns the numbers of
/// cuts and of second cuts.
fn cut_every_operation(saves: &[(usize, f32)]) -> (u32, u32) {
    let ids = [id("p0"), id("p1"), id("p2"), id("p3")];
    let mut flash = CutFlash::new();
    let mut committed = [None; 4];
    let (mut cuts, mut repair_cuts) = (0, 0);
    for (step, &(which, value)) in saves.iter().enumerate() {
        // The operations this save takes (load at boot, then the save), uncut.
        let mut s = ParamStore::new(flash.clone().power_back(), RANGE).unwrap();
        s.load(&ids, &mut [None; 4]);
        s.save(ids[which], value).unwrap();
        let done = s.into_flash();
        let operations = done.ops;
        for cut_at in 0..operations {
            let mut cut = flash.clone().power_back();
            cut.cut_at = Some(cut_at);
            let mut s = ParamStore::new(cut, RANGE).unwrap();
            s.load(&ids, &mut [None; 4]);
            assert!(
                s.save(ids[which], value).is_err(),
                "step {step} cut {cut_at}"
            );
            // Power back: a reset loads the store. When that load repairs (writes or erases),
            // the power goes again at each of the repair's operations first.
            let after_cut = s.into_flash().power_back();
            let mut probe = ParamStore::new(after_cut.clone(), RANGE).unwrap();
            probe.load(&ids, &mut [None; 4]);
            for second in 0..probe.into_flash().ops {
                let mut again = after_cut.clone();
                again.cut_at = Some(second);
                let mut s = ParamStore::new(again, RANGE).unwrap();
                s.load(&ids, &mut [None; 4]);
                let mut s = ParamStore::new(s.into_flash().power_back(), RANGE).unwrap();
                let mut values = [None; 4];
                s.load(&ids, &mut values);
                for k in 0..4 {
                    let ok = values[k] == committed[k] || (k == which && values[k] == Some(value));
                    assert!(
                        ok,
                        "step {step}, cuts at {cut_at} and repair's {second}: p{k}"
                    );
                }
                repair_cuts += 1;
            }
            let mut s = ParamStore::new(after_cut, RANGE).unwrap();
            let mut values = [None; 4];
            let report = s.load(&ids, &mut values);
            let context = || format!("step {step}, cut at operation {cut_at} of {operations}");
            if committed.iter().any(Option::is_some) {
                assert_eq!(report.status, StoreStatus::Ok, "{}", context());
            } else {
                assert!(
                    matches!(report.status, StoreStatus::Ok | StoreStatus::Empty),
                    "{}: {:?}",
                    context(),
                    report.status
                );
            }
            for k in 0..4 {
                if k == which {
                    assert!(
                        values[k] == committed[k] || values[k] == Some(value),
                        "{}: p{k} = {:?}, expected {:?} or {value}",
                        context(),
                        values[k],
                        committed[k]
                    );
                } else {
                    assert_eq!(values[k], committed[k], "{}: p{k}", context());
                }
            }
            // And the store takes the next save.
            s.save(ids[which], -1.0)
                .unwrap_or_else(|e| panic!("{}: {e}", context()));
            let mut after = [None; 4];
            s.load(&ids, &mut after);
            assert_eq!(after[which], Some(-1.0), "{}", context());
            cuts += 1;
        }
        flash = done;
        committed[which] = Some(value);
    }
    (cuts, repair_cuts)
}

#[test]
fn power_loss_at_every_byte_and_erase_keeps_the_old_or_the_new_value() {
    // 700 saves: the first formats the store (two erases), then about every 60th fills a
    // page, so the crate copies the live records and erases a page under the cuts too.
    let (cuts, repair_cuts) = cut_every_operation(&series(700));
    println!(
        "power loss: {cuts} cuts over 700 saves and {repair_cuts} more during the repairs, \
         every one loaded old or new"
    );
    assert!(cuts > 11_000, "{cuts} cuts");
    assert!(repair_cuts > 0, "no cut called for a repair");
}
