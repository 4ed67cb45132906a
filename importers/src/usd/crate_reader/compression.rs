//! The crate file's compression: TfFastCompression (LZ4 blocks) and the
//! integer coding of its index and integer arrays, bounded before decoding.

/// TfFastCompression: a chunk-count byte, then one LZ4 block (count 0) or
/// that many `i32 size` + block chunks.
pub(crate) fn fast_decompress(
    input: &[u8],
    max_output: u64,
) -> std::result::Result<Vec<u8>, String> {
    let (&chunks, mut rest) = input
        .split_first()
        .ok_or_else(|| "empty compressed buffer".to_string())?;
    let mut output = Vec::with_capacity((max_output as usize).min(input.len().saturating_mul(4)));
    if chunks == 0 {
        lz4_block(rest, &mut output, max_output)?;
        return Ok(output);
    }
    for chunk in 0..chunks {
        if rest.len() < 4 {
            return Err(format!("chunk {chunk} has no size"));
        }
        let size = i32::from_le_bytes([rest[0], rest[1], rest[2], rest[3]]);
        let size = usize::try_from(size).map_err(|_| format!("chunk {chunk} has negative size"))?;
        let block = rest
            .get(4..4 + size)
            .ok_or_else(|| format!("chunk {chunk} of {size} bytes overruns the buffer"))?;
        lz4_block(block, &mut output, max_output)?;
        rest = &rest[4 + size..];
    }
    Ok(output)
}

/// Decodes one LZ4 block, appending to `output` but never beyond `max_output`.
fn lz4_block(
    input: &[u8],
    output: &mut Vec<u8>,
    max_output: u64,
) -> std::result::Result<(), String> {
    let mut i = 0usize;
    let max = usize::try_from(max_output).unwrap_or(usize::MAX);
    let length = |i: &mut usize, mut value: usize| -> std::result::Result<usize, String> {
        if value == 15 {
            loop {
                let byte = *input.get(*i).ok_or("LZ4 length runs past the block")?;
                *i += 1;
                value = value
                    .checked_add(usize::from(byte))
                    .ok_or("LZ4 length overflows")?;
                if byte != 255 {
                    break;
                }
            }
        }
        Ok(value)
    };
    loop {
        let token = *input.get(i).ok_or("LZ4 block ends without a sequence")?;
        i += 1;
        let literals = length(&mut i, usize::from(token >> 4))?;
        let literal_bytes = input
            .get(i..i.saturating_add(literals))
            .ok_or("LZ4 literals run past the block")?;
        if output.len() + literals > max {
            return Err(format!(
                "LZ4 data decompresses to more than the expected {max} bytes"
            ));
        }
        output.extend_from_slice(literal_bytes);
        i += literals;
        if i == input.len() {
            return Ok(());
        }
        let offset_bytes = input
            .get(i..i + 2)
            .ok_or("LZ4 match offset runs past the block")?;
        let offset = usize::from(u16::from_le_bytes([offset_bytes[0], offset_bytes[1]]));
        i += 2;
        if offset == 0 || offset > output.len() {
            return Err(format!("LZ4 match offset {offset} points before the data"));
        }
        let match_length = length(&mut i, usize::from(token & 15))? + 4;
        if output.len() + match_length > max {
            return Err(format!(
                "LZ4 data decompresses to more than the expected {max} bytes"
            ));
        }
        let start = output.len() - offset;
        for k in 0..match_length {
            let byte = output[start + k];
            output.push(byte);
        }
    }
}

/// OpenUSD's integer coding: common value, 2-bit codes, then deltas of
/// 1/2/4 bytes (8-bit ints) or 2/4/8 bytes (64-bit ints).
pub(crate) fn decode_ints(
    buffer: &[u8],
    count: u64,
    wide: bool,
) -> std::result::Result<Vec<i64>, String> {
    let width = if wide { 8 } else { 4 };
    let code_bytes = usize::try_from(count.div_ceil(4)).map_err(|_| "too many integers")?;
    if buffer.len() < width + code_bytes {
        return Err(format!(
            "{} bytes cannot hold {count} coded integers",
            buffer.len()
        ));
    }
    let read = |bytes: &[u8]| -> i64 {
        match bytes.len() {
            1 => i64::from(bytes[0] as i8),
            2 => i64::from(i16::from_le_bytes([bytes[0], bytes[1]])),
            4 => i64::from(i32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]])),
            _ => {
                let mut raw = [0u8; 8];
                raw.copy_from_slice(&bytes[..8]);
                i64::from_le_bytes(raw)
            }
        }
    };
    let common = read(&buffer[..width]);
    let codes = &buffer[width..width + code_bytes];
    let mut data = &buffer[width + code_bytes..];
    let mut output = Vec::with_capacity(count as usize);
    let mut previous = 0i64;
    for index in 0..count as usize {
        let code = (codes[index / 4] >> (2 * (index % 4))) & 3;
        let size = match (code, wide) {
            (0, _) => 0,
            (1, false) => 1,
            (2, false) | (1, true) => 2,
            (3, false) | (2, true) => 4,
            _ => 8,
        };
        let delta = if size == 0 {
            common
        } else {
            let bytes = data
                .get(..size)
                .ok_or("coded integers run past the buffer")?;
            data = &data[size..];
            read(bytes)
        };
        previous = if wide {
            previous.wrapping_add(delta)
        } else {
            i64::from((previous as i32).wrapping_add(delta as i32))
        };
        output.push(previous);
    }
    Ok(output)
}
