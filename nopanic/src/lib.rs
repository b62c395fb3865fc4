//! The panic handler shared by the check's binaries.
//!
//! Normally it calls `capp_nopanic_panic_path_survived`, which no object
//! defines: if the optimised program still contains a call to the panic
//! machinery, the handler is reachable and the link fails naming that
//! symbol. With the `list` feature it loops instead, so the binary links and
//! `llvm-objdump` can show where the remaining panic calls are.
#![no_std]

#[cfg(not(feature = "list"))]
extern "C" {
    fn capp_nopanic_panic_path_survived() -> !;
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    #[cfg(not(feature = "list"))]
    // SAFETY: never runs: the link fails whenever this call is reachable.
    unsafe {
        capp_nopanic_panic_path_survived()
    }
    #[cfg(feature = "list")]
    loop {
        core::hint::spin_loop();
    }
}
