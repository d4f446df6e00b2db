//! Twil firmware for the STM32F405 (bring-up: a grid in static memory).
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use defmt_rtt as _;
use panic_probe as _;
use twil_core::grid::{Grid300, GridGeometry};

#[entry]
fn main() -> ! {
    let mut grid = Grid300::new(GridGeometry::seed_default()).unwrap();
    grid.fill_row(10, 0, 299);
    defmt::info!("twil firmware up: {} occupied cells", grid.count_occupied());
    loop {
        cortex_m::asm::wfi();
    }
}
