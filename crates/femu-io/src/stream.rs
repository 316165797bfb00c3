//! Files read as streams: ahead on another thread, so that the system's copy of the bytes
//! overlaps their parsing.

use std::io::{BufRead, Read};

/// A file read ahead on another thread in chunks of 4 MiB (two in flight, recycled), so that
/// the system's copy of the bytes overlaps their parsing (docs/SCALING.md, "Reading another
/// solver's matrices").
pub(crate) struct ReadAhead {
    full: std::sync::mpsc::Receiver<std::io::Result<Vec<u8>>>,
    empty: std::sync::mpsc::SyncSender<Vec<u8>>,
    chunk: Vec<u8>,
    pos: usize,
    done: bool,
}

impl ReadAhead {
    const CHUNK: usize = 4 << 20;

    pub(crate) fn new(mut file: std::fs::File) -> Self {
        let (full_tx, full) = std::sync::mpsc::sync_channel::<std::io::Result<Vec<u8>>>(2);
        let (empty, empty_rx) = std::sync::mpsc::sync_channel::<Vec<u8>>(4);
        std::thread::spawn(move || {
            loop {
                let mut buf = empty_rx
                    .try_recv()
                    .unwrap_or_else(|_| Vec::with_capacity(Self::CHUNK));
                buf.resize(Self::CHUNK, 0);
                match read_full(&mut file, &mut buf) {
                    Ok(0) => return,
                    Ok(n) => {
                        buf.truncate(n);
                        if full_tx.send(Ok(buf)).is_err() {
                            return; // the reader stopped (an error in the file)
                        }
                    }
                    Err(e) => {
                        let _ = full_tx.send(Err(e));
                        return;
                    }
                }
            }
        });
        ReadAhead {
            full,
            empty,
            chunk: Vec::new(),
            pos: 0,
            done: false,
        }
    }
}

impl Read for ReadAhead {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        let avail = self.fill_buf()?;
        let n = avail.len().min(out.len());
        out[..n].copy_from_slice(&avail[..n]);
        self.consume(n);
        Ok(n)
    }
}

impl BufRead for ReadAhead {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        while self.pos == self.chunk.len() && !self.done {
            match self.full.recv() {
                Ok(Ok(next)) => {
                    let used = std::mem::replace(&mut self.chunk, next);
                    let _ = self.empty.try_send(used);
                    self.pos = 0;
                }
                Ok(Err(e)) => return Err(e),
                Err(_) => self.done = true,
            }
        }
        Ok(&self.chunk[self.pos..])
    }

    fn consume(&mut self, n: usize) {
        self.pos += n;
    }
}

/// Reads until `buf` is full or the file ends; the bytes read.
pub(crate) fn read_full(r: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match r.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(got)
}

/// Reads one Fortran unformatted record (`length, bytes, length`, 4-byte lengths in the file's
/// byte order) starting at byte `at` into `buf` (cleared first): `Ok(false)` at the end of the
/// stream. `length`: the record's first four bytes when the caller has read them already. The
/// bytes are read as they come, so that a damaged length allocates no more than the stream holds.
///
/// # Errors
/// The stream's; [`IoError::Content`] naming byte `at` for a record cut by the end of the stream,
/// a negative length, or lengths that differ at its two ends.
pub(crate) fn fortran_record(
    reader: &mut impl Read,
    little: bool,
    at: u64,
    length: Option<[u8; 4]>,
    buf: &mut Vec<u8>,
    path: &std::path::Path,
) -> Result<bool, crate::IoError> {
    let content = |reason: String| crate::IoError::Content {
        path: path.to_path_buf(),
        reason: format!("byte {at}: {reason}"),
    };
    let io = |e| crate::IoError::io(path, e);
    let word = |b: [u8; 4]| {
        if little {
            i32::from_le_bytes(b)
        } else {
            i32::from_be_bytes(b)
        }
    };
    let head = match length {
        Some(h) => h,
        None => {
            let mut h = [0u8; 4];
            match read_full(reader, &mut h).map_err(io)? {
                0 => return Ok(false),
                4 => h,
                _ => {
                    return Err(content(
                        "truncated: the file ends inside a record's length".into(),
                    ));
                }
            }
        }
    };
    let n = word(head);
    let n = usize::try_from(n).map_err(|_| content(format!("a record of negative length {n}")))?;
    buf.clear();
    let got = reader.take(n as u64).read_to_end(buf).map_err(io)?;
    let mut tail = [0u8; 4];
    if got < n || read_full(reader, &mut tail).map_err(io)? < 4 {
        return Err(content(format!(
            "truncated: the record of {n} bytes runs past the end of the file"
        )));
    }
    let end = word(tail);
    if end as usize != n {
        return Err(content(format!(
            "the record says {n} bytes at its start and {end} at its end: not a Fortran record"
        )));
    }
    Ok(true)
}
