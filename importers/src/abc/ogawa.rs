//! Reading the Ogawa container: groups (lists of child references) and data
//! blocks (sized byte strings) at offsets in the file. Every offset and size
//! is checked against the file before it is used.

use crate::Place;

/// Bit 63 of a child reference marks a data block.
pub const DATA_BIT: u64 = 1 << 63;

/// A problem and where it is, before the file name is attached.
#[derive(Debug, Clone, PartialEq)]
pub struct Fault {
    pub place: Place,
    pub message: String,
}

impl Fault {
    pub fn at(offset: u64, message: impl Into<String>) -> Fault {
        Fault {
            place: Place::Offset(offset),
            message: message.into(),
        }
    }

    pub fn path(path: &str, message: impl Into<String>) -> Fault {
        Fault {
            place: Place::Path(path.to_string()),
            message: message.into(),
        }
    }
}

/// An Ogawa file held in memory.
pub struct Ogawa<'a> {
    bytes: &'a [u8],
    root: u64,
}

fn read_u64(bytes: &[u8], offset: u64) -> Option<u64> {
    let start = usize::try_from(offset).ok()?;
    let end = start.checked_add(8)?;
    let word: [u8; 8] = bytes.get(start..end)?.try_into().ok()?;
    Some(u64::from_le_bytes(word))
}

impl<'a> Ogawa<'a> {
    /// Checks the header: magic, frozen flag, version.
    pub fn open(bytes: &'a [u8]) -> Result<Ogawa<'a>, Fault> {
        if bytes.len() < 16 {
            return Err(Fault::at(
                0,
                format!(
                    "file of {} bytes is too short for an Ogawa header (16 bytes)",
                    bytes.len()
                ),
            ));
        }
        if &bytes[..5] != b"Ogawa" {
            return Err(Fault::at(
                0,
                "not an Alembic Ogawa file (no 'Ogawa' magic; HDF5 Alembic files are not supported)",
            ));
        }
        if bytes[5] != 0xFF {
            return Err(Fault::at(
                5,
                "the file is not frozen: its writer did not finish it (incomplete or still being written)",
            ));
        }
        let version = u16::from_be_bytes([bytes[6], bytes[7]]);
        if version != 1 {
            return Err(Fault::at(
                6,
                format!("unsupported Ogawa version {version} (expected 1)"),
            ));
        }
        let root = read_u64(bytes, 8).unwrap_or(0);
        Ok(Ogawa { bytes, root })
    }

    pub fn size(&self) -> u64 {
        self.bytes.len() as u64
    }

    pub fn root(&self) -> u64 {
        self.root
    }

    /// The child references of the group `reference` points at; an empty
    /// group (reference 0) has none.
    pub fn group(&self, reference: u64) -> Result<Vec<u64>, Fault> {
        if reference & DATA_BIT != 0 {
            return Err(Fault::at(
                reference & !DATA_BIT,
                "expected a group but the reference is to a data block",
            ));
        }
        if reference == 0 {
            return Ok(Vec::new());
        }
        let count = read_u64(self.bytes, reference).ok_or_else(|| {
            Fault::at(
                reference,
                format!(
                    "group offset is past the end of the file ({} bytes)",
                    self.size()
                ),
            )
        })?;
        let available = (self.size() - reference - 8) / 8;
        if count > available {
            return Err(Fault::at(
                reference,
                format!(
                    "group claims {count} children but only {available} fit before the end of the file"
                ),
            ));
        }
        let mut children = Vec::with_capacity(count as usize);
        for i in 0..count {
            let at = reference + 8 + 8 * i;
            children.push(read_u64(self.bytes, at).unwrap_or(0));
        }
        Ok(children)
    }

    /// The bytes of the data block `reference` points at; the empty-data
    /// reference gives no bytes.
    pub fn data(&self, reference: u64) -> Result<&'a [u8], Fault> {
        if reference & DATA_BIT == 0 {
            return Err(Fault::at(
                reference,
                "expected a data block but the reference is to a group",
            ));
        }
        let offset = reference & !DATA_BIT;
        if offset == 0 {
            return Ok(&[]);
        }
        let size = read_u64(self.bytes, offset).ok_or_else(|| {
            Fault::at(
                offset,
                format!(
                    "data offset is past the end of the file ({} bytes)",
                    self.size()
                ),
            )
        })?;
        let available = self.size() - offset - 8;
        if size > available {
            return Err(Fault::at(
                offset,
                format!("data block of {size} bytes runs past the end of the file ({available} bytes left)"),
            ));
        }
        let start = (offset + 8) as usize;
        Ok(&self.bytes[start..start + size as usize])
    }
}

/// True when `reference` is a data block.
pub fn is_data(reference: u64) -> bool {
    reference & DATA_BIT != 0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(body: &[u8], root: u64) -> Vec<u8> {
        let mut bytes = b"Ogawa\xff\x00\x01".to_vec();
        bytes.extend_from_slice(&root.to_le_bytes());
        bytes.extend_from_slice(body);
        bytes
    }

    #[test]
    fn reads_groups_and_data() {
        // Data "xy" at 16, group [data] at 26.
        let mut body = 2u64.to_le_bytes().to_vec();
        body.extend_from_slice(b"xy");
        body.extend_from_slice(&1u64.to_le_bytes());
        body.extend_from_slice(&(16 | DATA_BIT).to_le_bytes());
        let bytes = file(&body, 26);
        let ogawa = Ogawa::open(&bytes).unwrap();
        let children = ogawa.group(ogawa.root()).unwrap();
        assert_eq!(children, vec![16 | DATA_BIT]);
        assert_eq!(ogawa.data(children[0]).unwrap(), b"xy");
        assert_eq!(ogawa.data(DATA_BIT).unwrap(), b"");
        assert!(ogawa.group(0).unwrap().is_empty());
    }

    #[test]
    fn rejects_bad_headers_and_overruns() {
        assert!(Ogawa::open(b"Ogawa").is_err());
        assert!(Ogawa::open(b"Ogawa\x00\x00\x01\x00\x00\x00\x00\x00\x00\x00\x00").is_err());
        assert!(Ogawa::open(b"HDF5\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00").is_err());
        let bytes = file(&u64::MAX.to_le_bytes(), 16);
        let ogawa = Ogawa::open(&bytes).unwrap();
        assert!(ogawa.group(16).is_err());
        assert!(ogawa.data(16 | DATA_BIT).is_err());
        assert!(ogawa.group(1 << 40).is_err());
        assert!(ogawa.data(u64::MAX).is_err());
        assert!(ogawa.group(16 | DATA_BIT).is_err());
        assert!(ogawa.data(16).is_err());
    }
}
