//! bikedyn in the browser: the application library's jobs behind one
//! JSON-in, JSON-out entry point, compiled to `wasm32-unknown-unknown`.
//!
//! A request names its job and gives the job's options; the answer is the
//! job's typed result serialized as the command line serializes it
//! (`eig --format json`, `stability --json`, `canonical --json`, `sweep
//! --format json`, `models --json`), so a page and a script read the same
//! fields. Nothing is computed here: each job is one call of the library
//! (`explore`, the explorer's answer after a change, a few on one bicycle).
//!
//! The module exports a plain C interface (no JavaScript glue to generate),
//! which `wasm/explorer/bikedyn.js` wraps:
//!
//! - `bikedyn_alloc(len) -> ptr` and `bikedyn_free(ptr, len)`: a buffer in
//!   the module's memory for the request's UTF-8 bytes;
//! - `bikedyn_call(ptr, len) -> status` runs the request (0: the answer is
//!   the result, 1: the answer is an error `{"kind", "message"}`);
//! - `bikedyn_answer_ptr()`, `bikedyn_answer_len()`: the answer's UTF-8
//!   bytes, valid until the next call;
//! - `bikedyn_arrays_ptr()`, `bikedyn_arrays_len()`: the `f64` buffer that
//!   an answer's `arrays` field points into (`eig` with `arrays`), valid
//!   until the next call.
//!
//! A panic (a defect: the library returns typed errors) traps the call; its
//! message is kept for `bikedyn_panic_ptr()`/`bikedyn_panic_len()`, and the
//! page loads a fresh module.

mod arrays;
mod bicycle_answer;
mod explore;
mod request;

pub use request::{answer, reply, Answer, Reply};

#[cfg(target_arch = "wasm32")]
mod abi {
    use std::cell::RefCell;

    thread_local! {
        static ANSWER: RefCell<Vec<u8>> = const { RefCell::new(Vec::new()) };
        static PANIC: RefCell<Vec<u8>> = const { RefCell::new(Vec::new()) };
        static ARRAYS: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
    }

    /// A buffer of `len` bytes in the module's memory, for the caller to
    /// fill and pass to [`bikedyn_call`].
    #[no_mangle]
    pub extern "C" fn bikedyn_alloc(len: usize) -> *mut u8 {
        let mut v = Vec::<u8>::with_capacity(len.max(1));
        let p = v.as_mut_ptr();
        std::mem::forget(v);
        p
    }

    /// Frees a buffer of [`bikedyn_alloc`].
    ///
    /// # Safety
    /// `ptr` and `len` are those of one earlier `bikedyn_alloc` call, freed
    /// once.
    #[no_mangle]
    pub unsafe extern "C" fn bikedyn_free(ptr: *mut u8, len: usize) {
        drop(Vec::from_raw_parts(ptr, 0, len.max(1)));
    }

    /// Runs the JSON request in `ptr[..len]`; 0 when the answer is the
    /// result, 1 when it is an error.
    ///
    /// # Safety
    /// `ptr[..len]` is readable memory of the module (a buffer of
    /// [`bikedyn_alloc`]).
    #[no_mangle]
    pub unsafe extern "C" fn bikedyn_call(ptr: *const u8, len: usize) -> u32 {
        static HOOK: std::sync::Once = std::sync::Once::new();
        HOOK.call_once(|| {
            std::panic::set_hook(Box::new(|info| {
                PANIC.with(|p| *p.borrow_mut() = info.to_string().into_bytes());
            }))
        });
        let bytes = std::slice::from_raw_parts(ptr, len);
        let reply = super::reply(bytes);
        let (status, text) = match reply.answer {
            super::Answer::Result(t) => (0, t),
            super::Answer::Error(t) => (1, t),
        };
        ANSWER.with(|a| *a.borrow_mut() = text.into_bytes());
        ARRAYS.with(|a| *a.borrow_mut() = reply.arrays);
        status
    }

    /// The last answer's bytes.
    #[no_mangle]
    pub extern "C" fn bikedyn_answer_ptr() -> *const u8 {
        ANSWER.with(|a| a.borrow().as_ptr())
    }

    /// The last answer's length in bytes.
    #[no_mangle]
    pub extern "C" fn bikedyn_answer_len() -> usize {
        ANSWER.with(|a| a.borrow().len())
    }

    /// The last answer's arrays: the `f64` buffer that its `arrays` field
    /// points into (8-byte aligned).
    #[no_mangle]
    pub extern "C" fn bikedyn_arrays_ptr() -> *const f64 {
        ARRAYS.with(|a| a.borrow().as_ptr())
    }

    /// Its length in `f64` elements.
    #[no_mangle]
    pub extern "C" fn bikedyn_arrays_len() -> usize {
        ARRAYS.with(|a| a.borrow().len())
    }

    /// The message of the panic that trapped the last call.
    #[no_mangle]
    pub extern "C" fn bikedyn_panic_ptr() -> *const u8 {
        PANIC.with(|a| a.borrow().as_ptr())
    }

    /// Its length in bytes.
    #[no_mangle]
    pub extern "C" fn bikedyn_panic_len() -> usize {
        PANIC.with(|a| a.borrow().len())
    }
}
