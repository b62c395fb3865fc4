//! Boots the firmware under `qemu-system-arm -machine mps2-an386` with its
//! UART on a local TCP port, and connects a [`Link`] to it. Builds nothing:
//! build the firmware first (`cargo build --release` in `firmware/`).

use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use crate::{Link, LinkError};

/// The QEMU binary.
pub const QEMU: &str = "qemu-system-arm";

/// The default firmware ELF of this workspace (release build for mps2-an386).
pub fn default_elf() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../firmware/target/thumbv7em-none-eabihf/release/capp-firmware")
}

/// Whether `qemu-system-arm` can be run.
pub fn qemu_available() -> bool {
    Command::new(QEMU)
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .map(|s| s.success())
        .unwrap_or(false)
}

/// A running QEMU; killed when dropped.
pub struct Qemu {
    child: Child,
    /// The TCP port of the emulated UART.
    pub port: u16,
}

impl Qemu {
    /// Boots `elf` and connects to its UART. QEMU waits for the connection
    /// before it starts the CPU, so no byte is lost. Semihosting output (the
    /// defmt log) goes to `log` if given, else is discarded.
    pub fn launch(elf: &Path, log: Option<&Path>) -> Result<(Qemu, Link<TcpStream>), LinkError> {
        let (qemu, stream) = Qemu::boot(elf, log)?;
        stream.set_read_timeout(Some(Duration::from_millis(50)))?;
        stream.set_nodelay(true)?;
        Ok((qemu, Link::new(stream)))
    }

    /// [`Qemu::launch`], returning the raw connection to the UART (for a
    /// proxy, say) instead of a [`Link`].
    pub fn boot(elf: &Path, log: Option<&Path>) -> Result<(Qemu, TcpStream), LinkError> {
        let port = {
            let l = TcpListener::bind("127.0.0.1:0")?;
            l.local_addr()?.port()
        };
        let stdout = match log {
            Some(p) => Stdio::from(std::fs::File::create(p)?),
            None => Stdio::null(),
        };
        let child = Command::new(QEMU)
            .args(["-machine", "mps2-an386", "-nographic", "-monitor", "none"])
            .args(["-semihosting-config", "enable=on,target=native"])
            .arg("-serial")
            .arg(format!("tcp:127.0.0.1:{port},server=on,wait=on"))
            .arg("-kernel")
            .arg(elf)
            .stdin(Stdio::null())
            .stdout(stdout)
            .stderr(Stdio::inherit())
            .spawn()?;
        let mut qemu = Qemu { child, port };
        let deadline = Instant::now() + Duration::from_secs(20);
        loop {
            match TcpStream::connect(("127.0.0.1", port)) {
                Ok(stream) => return Ok((qemu, stream)),
                Err(e) => {
                    if let Ok(Some(status)) = qemu.child.try_wait() {
                        return Err(LinkError::Io(std::io::Error::other(format!(
                            "qemu exited: {status}"
                        ))));
                    }
                    if Instant::now() > deadline {
                        return Err(e.into());
                    }
                    std::thread::sleep(Duration::from_millis(50));
                }
            }
        }
    }

    /// Whether QEMU is still running.
    pub fn is_running(&mut self) -> bool {
        matches!(self.child.try_wait(), Ok(None))
    }
}

impl Drop for Qemu {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
