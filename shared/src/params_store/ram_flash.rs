//! A NOR flash in RAM: erased bytes read 0xFF, a write may only program erased bytes, erasing
//! works on whole pages. The QEMU build keeps its parameter store in one (QEMU 7.2's
//! `netduinoplus2` does not emulate flash programming or erasing), and the host tests build
//! their power-cut flash on it. Like the STM32F4's flash as `stm32f4xx-hal` drives it, it reads
//! and writes single bytes; unlike it, it forgets everything at reset.

use embedded_storage::nor_flash::{
    ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
};

/// Why a [`RamFlash`] operation was refused (nothing was changed).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RamFlashError {
    /// The range runs past the flash's end.
    OutOfBounds,
    /// An erase not on page boundaries.
    NotAligned,
    /// A write over a byte that is not erased (offset of the first one).
    NotErased(u32),
}

impl NorFlashError for RamFlashError {
    fn kind(&self) -> NorFlashErrorKind {
        match self {
            RamFlashError::OutOfBounds => NorFlashErrorKind::OutOfBounds,
            RamFlashError::NotAligned => NorFlashErrorKind::NotAligned,
            RamFlashError::NotErased(_) => NorFlashErrorKind::Other,
        }
    }
}

/// `BYTES` bytes of NOR flash in pages of `PAGE_BYTES`, erased at creation.
#[derive(Clone)]
pub struct RamFlash<const BYTES: usize, const PAGE_BYTES: usize> {
    bytes: [u8; BYTES],
}

impl<const BYTES: usize, const PAGE_BYTES: usize> Default for RamFlash<BYTES, PAGE_BYTES> {
    fn default() -> Self {
        Self::ERASED
    }
}

impl<const BYTES: usize, const PAGE_BYTES: usize> RamFlash<BYTES, PAGE_BYTES> {
    /// Every byte erased (usable in a `static`).
    pub const ERASED: Self = Self {
        bytes: [0xFF; BYTES],
    };

    /// The contents.
    pub fn as_bytes(&self) -> &[u8; BYTES] {
        &self.bytes
    }

    /// The contents, to change at will (tests: damage, a cut write).
    pub fn as_bytes_mut(&mut self) -> &mut [u8; BYTES] {
        &mut self.bytes
    }

    /// The bytes of `offset .. offset + len`, or `OutOfBounds`.
    fn range(offset: u32, len: usize) -> Result<core::ops::Range<usize>, RamFlashError> {
        let start = offset as usize;
        match start.checked_add(len) {
            Some(end) if end <= BYTES => Ok(start..end),
            _ => Err(RamFlashError::OutOfBounds),
        }
    }
}

impl<const BYTES: usize, const PAGE_BYTES: usize> ErrorType for RamFlash<BYTES, PAGE_BYTES> {
    type Error = RamFlashError;
}

impl<const BYTES: usize, const PAGE_BYTES: usize> ReadNorFlash for RamFlash<BYTES, PAGE_BYTES> {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        let r = Self::range(offset, bytes.len())?;
        bytes.copy_from_slice(&self.bytes[r]);
        Ok(())
    }

    fn capacity(&self) -> usize {
        BYTES
    }
}

impl<const BYTES: usize, const PAGE_BYTES: usize> NorFlash for RamFlash<BYTES, PAGE_BYTES> {
    const WRITE_SIZE: usize = 1;
    const ERASE_SIZE: usize = PAGE_BYTES;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        if to < from {
            return Err(RamFlashError::OutOfBounds);
        }
        let r = Self::range(from, (to - from) as usize)?;
        if PAGE_BYTES == 0 || r.start % PAGE_BYTES != 0 || r.end % PAGE_BYTES != 0 {
            return Err(RamFlashError::NotAligned);
        }
        self.bytes[r].fill(0xFF);
        Ok(())
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        let r = Self::range(offset, bytes.len())?;
        if let Some(i) = self.bytes[r.clone()].iter().position(|&b| b != 0xFF) {
            return Err(RamFlashError::NotErased(offset + i as u32));
        }
        self.bytes[r].copy_from_slice(bytes);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_only_erased_bytes_and_erases_whole_pages() {
        let mut f = RamFlash::<64, 16>::ERASED;
        f.write(3, &[1, 2]).unwrap();
        assert_eq!(f.write(4, &[9]), Err(RamFlashError::NotErased(4)));
        let mut back = [0; 3];
        f.read(2, &mut back).unwrap();
        assert_eq!(back, [0xFF, 1, 2]);
        assert_eq!(f.erase(0, 8), Err(RamFlashError::NotAligned));
        assert_eq!(f.erase(48, 80), Err(RamFlashError::OutOfBounds));
        assert_eq!(f.read(62, &mut back), Err(RamFlashError::OutOfBounds));
        f.erase(0, 16).unwrap();
        assert!(f.as_bytes().iter().all(|&b| b == 0xFF));
    }
}
