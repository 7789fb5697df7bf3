//! The few libfreenect 0.5 calls a depth camera needs (the crate's only
//! `unsafe`), and [`Device`], a safe Kinect v1 depth stream: 640×480 raw
//! 11-bit disparity frames, each with the device's 32-bit timestamp and the
//! CLOCK_MONOTONIC time its callback ran.
//!
//! Declarations checked against Debian's `/usr/include/libfreenect.h`
//! (0.5.3): every enum there carries a `…_DUMMY = 2147483647` member, so it
//! is a C `int` (4 bytes), and `freenect_frame_mode` is 24 bytes: `uint32_t
//! reserved`, `freenect_resolution resolution`, a union of 4-byte enums,
//! `int32_t bytes`, `int16_t width, height`, four `int8_t`s.
//!
//! libfreenect calls the depth callback from inside
//! `freenect_process_events_timeout`, on the thread that called it: the
//! callback only copies the frame into a buffer allocated up front, owned
//! by a boxed `Shared` whose address libfreenect keeps as the device's
//! user pointer.

use std::ffi::{c_int, c_void};
use std::time::{Duration, Instant};

use crate::{FreenectError, HEIGHT, PIXELS, WIDTH};

#[repr(C)]
struct FreenectContext {
    _opaque: [u8; 0],
}

#[repr(C)]
struct FreenectDevice {
    _opaque: [u8; 0],
}

/// `freenect_frame_mode` (libfreenect.h), 24 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
struct FrameMode {
    reserved: u32,
    resolution: c_int,
    /// the union of `video_format` / `depth_format` (4-byte enums)
    format: i32,
    /// whole frame [bytes]
    bytes: i32,
    /// [px]
    width: i16,
    /// [px]
    height: i16,
    data_bits_per_pixel: i8,
    padding_bits_per_pixel: i8,
    /// [Hz]
    framerate: i8,
    is_valid: i8,
}

const _: () = assert!(std::mem::size_of::<FrameMode>() == 24);
const _: () = assert!(std::mem::align_of::<FrameMode>() == 4);
// offsets as gcc lays out the header's struct (checked with offsetof)
const _: () = assert!(std::mem::offset_of!(FrameMode, bytes) == 12);
const _: () = assert!(std::mem::offset_of!(FrameMode, width) == 16);
const _: () = assert!(std::mem::offset_of!(FrameMode, is_valid) == 23);

/// `FREENECT_RESOLUTION_MEDIUM`: 640×480.
const RESOLUTION_MEDIUM: c_int = 1;
/// `FREENECT_DEPTH_11BIT`: 11-bit disparity in one `uint16_t` a pixel.
const DEPTH_11BIT: c_int = 0;
/// `FREENECT_DEVICE_CAMERA`: the cameras only (no motor, no audio).
const DEVICE_CAMERA: c_int = 0x02;
/// `FREENECT_LOG_FATAL`: libfreenect silent but for fatal errors (the
/// service reports its own errors in one line).
const LOG_FATAL: c_int = 0;

type DepthCb = extern "C" fn(dev: *mut FreenectDevice, depth: *mut c_void, timestamp: u32);

#[link(name = "freenect")]
extern "C" {
    fn freenect_init(ctx: *mut *mut FreenectContext, usb_ctx: *mut c_void) -> c_int;
    fn freenect_shutdown(ctx: *mut FreenectContext) -> c_int;
    fn freenect_set_log_level(ctx: *mut FreenectContext, level: c_int);
    fn freenect_select_subdevices(ctx: *mut FreenectContext, subdevs: c_int);
    fn freenect_num_devices(ctx: *mut FreenectContext) -> c_int;
    fn freenect_open_device(
        ctx: *mut FreenectContext,
        dev: *mut *mut FreenectDevice,
        index: c_int,
    ) -> c_int;
    fn freenect_close_device(dev: *mut FreenectDevice) -> c_int;
    fn freenect_find_depth_mode(res: c_int, fmt: c_int) -> FrameMode;
    fn freenect_set_depth_mode(dev: *mut FreenectDevice, mode: FrameMode) -> c_int;
    fn freenect_set_depth_callback(dev: *mut FreenectDevice, cb: DepthCb);
    fn freenect_set_user(dev: *mut FreenectDevice, user: *mut c_void);
    fn freenect_get_user(dev: *mut FreenectDevice) -> *mut c_void;
    fn freenect_start_depth(dev: *mut FreenectDevice) -> c_int;
    fn freenect_stop_depth(dev: *mut FreenectDevice) -> c_int;
    fn freenect_process_events_timeout(
        ctx: *mut FreenectContext,
        timeout: *mut libc::timeval,
    ) -> c_int;
}

/// What the callback writes: the newest frame, owned by the [`Device`]
/// (boxed: its address is libfreenect's user pointer).
struct Shared {
    /// raw 11-bit disparity, [`PIXELS`] values, allocated up front
    buf: Vec<u16>,
    /// a frame was copied into `buf` since the last [`Device::next_frame`]
    ready: bool,
    /// the device's timestamp of that frame [60 MHz ticks, wraps]
    timestamp: u32,
    /// when the callback ran [ns, CLOCK_MONOTONIC]
    callback_mono_ns: u64,
    /// frames delivered while the previous one was still unread
    overwritten: u64,
}

/// The depth callback: copy the frame, note the times. No allocation, no
/// panic.
extern "C" fn depth_callback(dev: *mut FreenectDevice, depth: *mut c_void, timestamp: u32) {
    let now = phri_runtime::now_ns();
    // SAFETY: `dev` is the device libfreenect calls us for; its user
    // pointer was set by Device::open to a live Box<Shared> (the device is
    // closed before the box is freed), and the callback runs on the thread
    // inside freenect_process_events_timeout, while Device holds no
    // reference into the box
    let shared = unsafe { freenect_get_user(dev) }.cast::<Shared>();
    if shared.is_null() || depth.is_null() {
        return;
    }
    // SAFETY: as above: the only access to the box while this runs
    let shared = unsafe { &mut *shared };
    let bytes = shared.buf.len() * std::mem::size_of::<u16>();
    // SAFETY: libfreenect hands a frame of the depth mode's `bytes`, which
    // Device::open checked is 640×480×2 = `bytes`; copied as bytes (no
    // alignment assumed of libfreenect's buffer)
    unsafe {
        std::ptr::copy_nonoverlapping(
            depth.cast::<u8>(),
            shared.buf.as_mut_ptr().cast::<u8>(),
            bytes,
        );
    }
    if shared.ready {
        shared.overwritten += 1;
    }
    shared.ready = true;
    shared.timestamp = timestamp;
    shared.callback_mono_ns = now;
}

/// One depth frame as the device sent it.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// raw 11-bit disparity, row-major, 640×480 (2047: no reading)
    pub raw: Vec<u16>,
    /// the device's timestamp [60 MHz ticks, wraps every ~71.6 s]
    pub timestamp: u32,
    /// when the callback ran [ns, CLOCK_MONOTONIC]
    pub callback_mono_ns: u64,
}

/// A Kinect v1's depth stream (the camera subdevice only), opened and
/// started; stopped and closed on drop.
pub struct Device {
    index: u32,
    ctx: *mut FreenectContext,
    dev: *mut FreenectDevice,
    /// the callback's state (`Box::into_raw`, freed on drop)
    shared: *mut Shared,
    /// a buffer to swap in for the next frame
    spare: Option<Vec<u16>>,
}

impl Device {
    /// Open Kinect `index` among libfreenect's devices and start its depth
    /// stream in 640×480 11-bit disparity.
    pub fn open(index: u32) -> Result<Device, FreenectError> {
        let mut ctx: *mut FreenectContext = std::ptr::null_mut();
        // SAFETY: a valid out-pointer; a null usb context asks libfreenect
        // for its own
        let rc = unsafe { freenect_init(&mut ctx, std::ptr::null_mut()) };
        if rc < 0 || ctx.is_null() {
            return Err(FreenectError::Call {
                index,
                call: "freenect_init",
                code: rc,
            });
        }
        let mut device = Device {
            index,
            ctx,
            dev: std::ptr::null_mut(),
            shared: std::ptr::null_mut(),
            spare: None,
        };
        // SAFETY: a context freenect_init gave
        let count = unsafe {
            freenect_set_log_level(ctx, LOG_FATAL);
            freenect_select_subdevices(ctx, DEVICE_CAMERA);
            freenect_num_devices(ctx)
        };
        if count < 0 || index as i64 >= count as i64 {
            return Err(FreenectError::NoDevice {
                index,
                count: count.max(0) as u32,
            });
        }
        let mut dev: *mut FreenectDevice = std::ptr::null_mut();
        // SAFETY: a live context, a valid out-pointer, an index below the count
        let rc = unsafe { freenect_open_device(ctx, &mut dev, index as c_int) };
        if rc < 0 || dev.is_null() {
            return Err(FreenectError::Call {
                index,
                call: "freenect_open_device",
                code: rc,
            });
        }
        device.dev = dev;
        // SAFETY: plain values in, a struct by value out
        let mode = unsafe { freenect_find_depth_mode(RESOLUTION_MEDIUM, DEPTH_11BIT) };
        let expected_bytes = (PIXELS * std::mem::size_of::<u16>()) as i32;
        if mode.is_valid == 0
            || mode.width as u32 != WIDTH
            || mode.height as u32 != HEIGHT
            || mode.bytes != expected_bytes
        {
            return Err(FreenectError::Mode {
                index,
                width: mode.width,
                height: mode.height,
                bytes: mode.bytes,
            });
        }
        // SAFETY: an open device, a mode libfreenect returned
        let rc = unsafe { freenect_set_depth_mode(dev, mode) };
        if rc < 0 {
            return Err(FreenectError::Call {
                index,
                call: "freenect_set_depth_mode",
                code: rc,
            });
        }
        let shared = Box::new(Shared {
            buf: vec![0; PIXELS],
            ready: false,
            timestamp: 0,
            callback_mono_ns: 0,
            overwritten: 0,
        });
        device.shared = Box::into_raw(shared);
        // SAFETY: an open device; the user pointer stays valid until drop,
        // which closes the device before freeing it
        let rc = unsafe {
            freenect_set_user(dev, device.shared.cast::<c_void>());
            freenect_set_depth_callback(dev, depth_callback);
            freenect_start_depth(dev)
        };
        if rc < 0 {
            return Err(FreenectError::Call {
                index,
                call: "freenect_start_depth",
                code: rc,
            });
        }
        Ok(device)
    }

    /// The device's index among libfreenect's devices.
    pub fn index(&self) -> u32 {
        self.index
    }

    /// Frames the device delivered that were overwritten before being read.
    pub fn overwritten(&self) -> u64 {
        // SAFETY: the box lives as long as self; no callback runs now (only
        // inside next_frame)
        unsafe { (*self.shared).overwritten }
    }

    /// The next depth frame, waiting at most about `timeout` for it
    /// ([`FreenectError::Timeout`] if none came; under fakenect, whose event
    /// processing ignores the timeout, up to one recorded frame interval
    /// longer). A failed event processing is [`FreenectError::Events`].
    pub fn next_frame(&mut self, timeout: Duration) -> Result<Frame, FreenectError> {
        let start = Instant::now();
        loop {
            if let Some(frame) = self.take() {
                return Ok(frame);
            }
            let left = timeout.saturating_sub(start.elapsed());
            if left.is_zero() {
                return Err(FreenectError::Timeout {
                    index: self.index,
                    waited_ms: timeout.as_millis() as u64,
                });
            }
            let mut tv = libc::timeval {
                tv_sec: left.as_secs() as libc::time_t,
                tv_usec: left.subsec_micros() as libc::suseconds_t,
            };
            // SAFETY: a live context, a valid timeval; the callback it may
            // call touches only the box, which no reference of ours points
            // into now
            let rc = unsafe { freenect_process_events_timeout(self.ctx, &mut tv) };
            if rc < 0 {
                return match self.take() {
                    Some(frame) => Ok(frame),
                    None => Err(FreenectError::Events {
                        index: self.index,
                        code: rc,
                    }),
                };
            }
        }
    }

    /// Give a frame's buffer back for a later frame (saves an allocation).
    pub fn recycle(&mut self, frame: Frame) {
        if frame.raw.len() == PIXELS {
            self.spare = Some(frame.raw);
        }
    }

    /// The frame the callback copied, if one is waiting.
    fn take(&mut self) -> Option<Frame> {
        // SAFETY: the box lives as long as self; no callback runs now
        let shared = unsafe { &mut *self.shared };
        if !shared.ready {
            return None;
        }
        shared.ready = false;
        let fresh = self.spare.take().unwrap_or_else(|| vec![0; PIXELS]);
        let raw = std::mem::replace(&mut shared.buf, fresh);
        Some(Frame {
            raw,
            timestamp: shared.timestamp,
            callback_mono_ns: shared.callback_mono_ns,
        })
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: pointers from open (null when not reached); the device is
        // stopped and closed before the box it calls back into is freed
        unsafe {
            if !self.dev.is_null() {
                if !self.shared.is_null() {
                    freenect_stop_depth(self.dev);
                }
                freenect_close_device(self.dev);
            }
            if !self.ctx.is_null() {
                freenect_shutdown(self.ctx);
            }
            if !self.shared.is_null() {
                drop(Box::from_raw(self.shared));
            }
        }
    }
}
