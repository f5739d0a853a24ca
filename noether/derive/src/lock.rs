//! One symbolica user at a time on this machine: unlicensed symbolica kills a second thread or
//! process that uses it while another thread that used it is alive, so every derivation takes
//! an exclusive lock on a per-user file first and keeps it until the thread that used symbolica
//! has ended (`lagra-derive` until it exits); a second one waits, saying so, instead of being
//! killed.

use std::fs::{File, OpenOptions, TryLockError};
use std::path::PathBuf;

/// Held for as long as symbolica may be in use.
pub struct Exclusive {
    _file: File,
}

fn path() -> PathBuf {
    let user = std::env::var("USER").unwrap_or_else(|_| "user".into());
    std::env::temp_dir().join(format!("lagra-symbolica-{user}.lock"))
}

impl Exclusive {
    /// Takes the lock, waiting for another derivation to finish if one holds it.
    pub fn take() -> Result<Exclusive, String> {
        let p = path();
        let f = OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&p)
            .map_err(|e| format!("cannot open {}: {e}", p.display()))?;
        match f.try_lock() {
            Ok(()) => Ok(Exclusive { _file: f }),
            Err(TryLockError::WouldBlock) => {
                eprintln!(
                    "lagra-derive: another symbolica derivation is running (lock {}); waiting for it",
                    p.display()
                );
                f.lock().map_err(|e| format!("cannot lock {}: {e}", p.display()))?;
                Ok(Exclusive { _file: f })
            }
            Err(TryLockError::Error(e)) => Err(format!("cannot lock {}: {e}", p.display())),
        }
    }
}
