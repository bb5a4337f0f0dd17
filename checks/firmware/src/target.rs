//! What the target binaries share: the board, semihosting (output, command line and
//! exit), SysTick as an instruction counter, stack painting, and the fault and panic
//! handlers.
//!
//! Semihosting on ARMv7-M: `bkpt 0xab` with the operation in r0 and its argument in r1
//! (ARM "Semihosting for AArch32 and AArch64", version 2). QEMU implements it with
//! `-semihosting-config enable=on,target=native`.
#![allow(dead_code)]

use core::arch::asm;
use core::fmt::{self, Write};
use cortex_m_rt::{exception, ExceptionFrame};

#[cfg(all(feature = "mps2-an386", not(feature = "mps2-an500")))]
mod board {
    /// The board's name (QEMU's machine).
    pub const BOARD: &str = "mps2-an386";
    /// The scalar: the Cortex-M4F's FPU is single precision.
    pub type R = f32;
    /// Its name.
    pub const SCALAR: &str = "f32";
    /// The S2 runs.
    pub const RUNS: [structomat_firmware::S2Run; 4] = structomat_firmware::RUNS_F32;
    /// Whether a 1 kHz loop spreads each event's work over the steps after it
    /// (`TwinSettings::spread_events`): on the M4F in f32 that keeps S2's worst step
    /// within the period's 112,000 instructions (228,280 unspread).
    pub const SPREAD: bool = true;
}

#[cfg(all(feature = "mps2-an500", not(feature = "mps2-an386")))]
mod board {
    /// The board's name (QEMU's machine).
    pub const BOARD: &str = "mps2-an500";
    /// The scalar: the Cortex-M7's FPU is double precision.
    pub type R = f64;
    /// Its name.
    pub const SCALAR: &str = "f64";
    /// The S2 runs.
    pub const RUNS: [structomat_firmware::S2Run; 3] = structomat_firmware::RUNS_F64;
    /// Whether a 1 kHz loop spreads each event's work over the steps after it: not on
    /// the M7 in f64, where the steps after a catch need sub-steps and a spread run's
    /// worst step (382,560) is dearer than an unspread one's (317,520).
    pub const SPREAD: bool = false;
}

pub use board::*;

const SYS_WRITE0: u32 = 0x04;
const SYS_GET_CMDLINE: u32 = 0x15;
const SYS_EXIT: u32 = 0x18;
/// ADP_Stopped_ApplicationExit: QEMU exits with status 0.
const ADP_STOPPED_APPLICATION_EXIT: u32 = 0x2_0026;
/// ADP_Stopped_RunTimeErrorUnknown: QEMU exits with status 1.
const ADP_STOPPED_RUNTIME_ERROR: u32 = 0x2_0023;

/// One semihosting call.
///
/// # Safety
/// `arg` must be what operation `op` expects (a pointer to a NUL-terminated string for
/// SYS_WRITE0, a reason code for SYS_EXIT).
unsafe fn semihosting(op: u32, arg: u32) -> u32 {
    let r: u32;
    // SAFETY: the debugger (QEMU) services the breakpoint; the caller vouches for `arg`.
    unsafe {
        asm!("bkpt #0xab", inout("r0") op => r, in("r1") arg, options(nostack));
    }
    r
}

/// The last word of the command line the debugger passes (QEMU: the image's path, then
/// `-append`'s words), read into `buf`; empty if none.
pub fn command_word(buf: &mut [u8; 128]) -> &[u8] {
    // The parameter block: the buffer and its length, which the call sets to the
    // command line's length.
    let mut block = [buf.as_mut_ptr() as u32, buf.len() as u32];
    // SAFETY: SYS_GET_CMDLINE writes at most `block[1]` bytes into the buffer.
    let failed = unsafe { semihosting(SYS_GET_CMDLINE, block.as_mut_ptr() as u32) } != 0;
    let len = if failed {
        0
    } else {
        (block[1] as usize).min(buf.len())
    };
    let line = &buf[..len];
    match line.iter().rposition(|&b| b == b' ') {
        Some(space) => &line[space + 1..],
        None => line,
    }
}

/// Executes an undefined instruction: a UsageFault, escalated to HardFault (the
/// configurable faults are off).
pub fn fault_now() -> ! {
    // SAFETY: it faults; the HardFault handler ends the run.
    unsafe { asm!("udf #0", options(noreturn)) }
}

/// Ends the emulation: QEMU's exit status 0 when `ok`, 1 otherwise.
pub fn exit(ok: bool) -> ! {
    let reason = if ok {
        ADP_STOPPED_APPLICATION_EXIT
    } else {
        ADP_STOPPED_RUNTIME_ERROR
    };
    // SAFETY: SYS_EXIT takes the reason code itself on AArch32.
    unsafe {
        semihosting(SYS_EXIT, reason);
    }
    // Without a debugger nothing ends the run: stop here.
    loop {
        core::hint::spin_loop();
    }
}

/// Semihosting output, a line at a time (one SYS_WRITE0 a line).
pub struct Out {
    buf: [u8; 512],
    len: usize,
}

impl Out {
    /// An empty line.
    pub const fn new() -> Self {
        Out {
            buf: [0; 512],
            len: 0,
        }
    }

    /// Writes `args` and a newline.
    pub fn line(&mut self, args: fmt::Arguments) {
        // A line longer than the buffer is cut (`flush` writes what fits).
        let _ = self.write_fmt(args);
        let _ = self.write_str("\n");
    }

    fn flush(&mut self) {
        self.buf[self.len] = 0;
        // SAFETY: the buffer is NUL-terminated at `len`, which is below its length.
        unsafe {
            semihosting(SYS_WRITE0, self.buf.as_ptr() as u32);
        }
        self.len = 0;
    }
}

impl Write for Out {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        for &b in s.as_bytes() {
            self.buf[self.len] = b;
            self.len += 1;
            if b == b'\n' || self.len == self.buf.len() - 1 {
                self.flush();
            }
        }
        Ok(())
    }
}

const SYST_CSR: *mut u32 = 0xE000_E010 as *mut u32;
const SYST_RVR: *mut u32 = 0xE000_E014 as *mut u32;
const SYST_CVR: *mut u32 = 0xE000_E018 as *mut u32;
/// SysTick's counter is 24 bits wide.
const SYST_MASK: u32 = 0x00FF_FFFF;

/// Instructions per SysTick tick under `-icount shift=0`: one instruction a virtual
/// nanosecond, and the MPS2's processor clock (SysTick's CLKSOURCE = 1) is the 25 MHz
/// SYSCLK of QEMU's model (`hw/arm/mps2.c`), 40 ns a tick. [`SysTick::calibrate`]
/// measures it; `run` checks the two agree.
pub const INSTRUCTIONS_PER_TICK: u32 = 40;

/// SysTick, free-running down from 2^24 − 1 on the processor clock, as an instruction
/// counter (resolution [`INSTRUCTIONS_PER_TICK`]; a stretch must stay under 2^24 ticks,
/// 671 M instructions).
pub struct SysTick {
    mark: u32,
}

impl SysTick {
    /// Starts the counter.
    pub fn start() -> Self {
        // SAFETY: the SysTick registers of the ARMv7-M System Control Space; nothing else
        // in these binaries uses SysTick.
        unsafe {
            SYST_RVR.write_volatile(SYST_MASK);
            SYST_CVR.write_volatile(0);
            // ENABLE | CLKSOURCE (processor clock), no interrupt.
            SYST_CSR.write_volatile(0b101);
        }
        SysTick { mark: 0 }
    }

    fn now() -> u32 {
        // SAFETY: reading SysTick's current value has no side effect.
        unsafe { SYST_CVR.read_volatile() }
    }

    /// Remembers now.
    pub fn mark(&mut self) {
        self.mark = Self::now();
    }

    /// Ticks since [`SysTick::mark`].
    pub fn ticks(&self) -> u32 {
        self.mark.wrapping_sub(Self::now()) & SYST_MASK
    }

    /// Instructions since [`SysTick::mark`].
    pub fn instructions(&self) -> u32 {
        self.ticks() * INSTRUCTIONS_PER_TICK
    }

    /// A loop of a known number of instructions (`subs` + `bne`, 2 an iteration) and
    /// the ticks it took: `(instructions, ticks)`.
    pub fn calibrate(&mut self) -> (u32, u32) {
        const ITERATIONS: u32 = 1_000_000;
        self.mark();
        // SAFETY: a register-only countdown loop.
        unsafe {
            asm!(
                "2:",
                "subs {n}, {n}, #1",
                "bne 2b",
                n = inout(reg) ITERATIONS => _,
                options(nomem, nostack),
            );
        }
        (2 * ITERATIONS, self.ticks())
    }
}

/// Stack painting: the free RAM below the caller's frame is filled with a pattern, and
/// the deepest word overwritten since is the stack's high-water mark.
pub mod stack {
    use core::sync::atomic::{AtomicUsize, Ordering};

    const PAINT: u32 = 0x5AC3_5AC3;
    /// How far below the top of RAM is painted: more than any use of the stack seen
    /// (issue 18: 6.8 KiB for an f32 step; the by-value construction a few twins' sizes).
    const DEPTH: usize = 1024 * 1024;
    /// Where the last paint started: the stack pointer of its caller, near enough.
    static BASE: AtomicUsize = AtomicUsize::new(0);

    extern "C" {
        /// The initial stack pointer (cortex-m-rt's `link.x`): the top of RAM.
        static _stack_start: u32;
    }

    fn bottom() -> usize {
        // Only the symbol's address is taken.
        core::ptr::addr_of!(_stack_start) as usize - DEPTH
    }

    /// Paints the stack below this function's frame down to [`DEPTH`] below the top.
    #[inline(never)]
    pub fn paint() {
        let here = 0u32;
        let sp = core::ptr::addr_of!(here) as usize & !3;
        BASE.store(sp, Ordering::Relaxed);
        // Leave this function's own frame and what it calls untouched.
        let end = sp - 256;
        let mut p = bottom();
        while p < end {
            // SAFETY: RAM between the statics and the live stack, which nothing uses
            // (the statics end far below `bottom()`: 4 MiB of RAM, < 1 MiB of statics).
            unsafe { (p as *mut u32).write_volatile(PAINT) };
            p += 4;
        }
    }

    /// The deepest stack use since [`paint`], bytes below the frame that called it.
    pub fn used() -> usize {
        let base = BASE.load(Ordering::Relaxed);
        let mut p = bottom();
        // SAFETY: reads of the painted region.
        while p < base && unsafe { (p as *const u32).read_volatile() } == PAINT {
            p += 4;
        }
        base - p
    }
}

/// The HardFault handler: the faulting frame, then a failed exit (a fault would
/// otherwise hang the emulation until its timeout).
#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    let mut out = Out::new();
    out.line(format_args!(
        "HARDFAULT pc {:#010x} lr {:#010x} xpsr {:#010x}",
        frame.pc(),
        frame.lr(),
        frame.xpsr()
    ));
    exit(false)
}

/// The panic handler: the message, then a failed exit.
#[panic_handler]
fn panicked(info: &core::panic::PanicInfo) -> ! {
    let mut out = Out::new();
    out.line(format_args!("PANIC {info}"));
    exit(false)
}
