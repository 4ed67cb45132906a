//! The Ogawa container: a tree of groups (lists of child references) and
//! data blocks (sized byte strings). Data blocks are streamed to the file as
//! they come; a group is written once all its children are, so groups end up
//! after their data and the root group last. The header's frozen byte stays
//! 0x00 until everything else is written.

use std::io::{self, Seek, SeekFrom, Write};

/// Bit 63 of a child reference marks a data block.
pub const DATA_BIT: u64 = 1 << 63;
/// Reference of an empty data block.
pub const EMPTY_DATA: u64 = DATA_BIT;
/// Reference of an empty group.
pub const EMPTY_GROUP: u64 = 0;

const HEADER_SIZE: u64 = 16;
const FROZEN_OFFSET: u64 = 5;
const ROOT_OFFSET: u64 = 8;

/// Writes an Ogawa file front to back.
pub struct OgawaWriter<W: Write + Seek> {
    out: W,
    position: u64,
}

impl<W: Write + Seek> OgawaWriter<W> {
    /// Writes the header, not frozen and without a root yet.
    pub fn new(mut out: W) -> io::Result<OgawaWriter<W>> {
        out.write_all(b"Ogawa")?;
        out.write_all(&[0x00, 0x00, 0x01])?;
        out.write_all(&0u64.to_le_bytes())?;
        Ok(OgawaWriter {
            out,
            position: HEADER_SIZE,
        })
    }

    /// Writes one data block made of `parts` one after another; returns its
    /// reference (the empty-data reference when there are no bytes).
    pub fn data(&mut self, parts: &[&[u8]]) -> io::Result<u64> {
        let size: u64 = parts.iter().map(|p| p.len() as u64).sum();
        if size == 0 {
            return Ok(EMPTY_DATA);
        }
        let start = self.position;
        self.out.write_all(&size.to_le_bytes())?;
        for part in parts {
            self.out.write_all(part)?;
        }
        self.position += 8 + size;
        Ok(start | DATA_BIT)
    }

    /// Writes a group of already written children; an empty group is not
    /// written at all (reference 0).
    pub fn group(&mut self, children: &[u64]) -> io::Result<u64> {
        if children.is_empty() {
            return Ok(EMPTY_GROUP);
        }
        let start = self.position;
        self.out.write_all(&(children.len() as u64).to_le_bytes())?;
        for child in children {
            self.out.write_all(&child.to_le_bytes())?;
        }
        self.position += 8 + 8 * children.len() as u64;
        Ok(start)
    }

    /// Points the header at the root group, then sets the frozen byte: only
    /// now is the file complete for readers.
    pub fn finish(mut self, root: u64) -> io::Result<W> {
        self.out.seek(SeekFrom::Start(ROOT_OFFSET))?;
        self.out.write_all(&root.to_le_bytes())?;
        self.out.flush()?;
        self.out.seek(SeekFrom::Start(FROZEN_OFFSET))?;
        self.out.write_all(&[0xFF])?;
        self.out.seek(SeekFrom::End(0))?;
        self.out.flush()?;
        Ok(self.out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    #[test]
    fn layout_of_a_small_file() {
        let mut writer = OgawaWriter::new(Cursor::new(Vec::new())).unwrap();
        let data = writer.data(&[b"ab", b"c"]).unwrap();
        let empty = writer.data(&[]).unwrap();
        let root = writer.group(&[data, empty, EMPTY_GROUP]).unwrap();
        let bytes = writer.finish(root).unwrap().into_inner();
        assert_eq!(&bytes[..8], b"Ogawa\xff\x00\x01");
        assert_eq!(u64::from_le_bytes(bytes[8..16].try_into().unwrap()), root);
        assert_eq!(data, 16 | DATA_BIT);
        assert_eq!(&bytes[16..24], &3u64.to_le_bytes());
        assert_eq!(&bytes[24..27], b"abc");
        assert_eq!(root, 27);
        assert_eq!(&bytes[27..35], &3u64.to_le_bytes());
        assert_eq!(&bytes[35..43], &data.to_le_bytes());
        assert_eq!(&bytes[43..51], &EMPTY_DATA.to_le_bytes());
        assert_eq!(&bytes[51..59], &0u64.to_le_bytes());
        assert_eq!(bytes.len(), 59);
    }
}
