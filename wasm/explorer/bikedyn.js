// bikedyn's WebAssembly module, for a page or for Node.js: one function,
// `call(request)`, that sends a JSON request to the module and returns the
// job's result (or throws a BikedynError with the library's message).
// The requests are documented in wasm/README.md.
//
// A classic script, not an ES module, so that a page opened as a file
// (file://, where Chromium refuses module imports and fetch) can load it:
// in a page it defines the globals `Bikedyn`, `BikedynError`,
// `BikedynWorkers` (the module in Web Workers, for the stability map) and
// `bikedynBytesFromBase64`; in Node.js they are the exports of a CommonJS
// module, which `import { Bikedyn, BikedynError } from ".../bikedyn.js"`
// also reads.
(function (root, factory) {
  const api = factory();
  // A worker runs this same code: its script is the factory's own text
  // (a page opened as a file may not fetch this file to hand it over).
  api.Bikedyn.workerFactory = factory.toString();
  if (typeof module === "object" && module && module.exports) {
    module.exports.Bikedyn = api.Bikedyn;
    module.exports.BikedynError = api.BikedynError;
    module.exports.BikedynWorkers = api.BikedynWorkers;
    module.exports.bikedynBytesFromBase64 = api.bikedynBytesFromBase64;
  } else {
    root.Bikedyn = api.Bikedyn;
    root.BikedynError = api.BikedynError;
    root.BikedynWorkers = api.BikedynWorkers;
    root.bikedynBytesFromBase64 = api.bikedynBytesFromBase64;
  }
})(typeof globalThis !== "undefined" ? globalThis : this, function () {
  "use strict";

  /** An error the library returned: `kind` is `request`, `bicycle` or `job`. */
  class BikedynError extends Error {
    constructor(kind, message) {
      super(message);
      this.name = "BikedynError";
      this.kind = kind;
    }
  }

  // The report crate's figures (plotters) are compiled into the module but
  // never drawn there: plotters imports these functions of wasm-bindgen for
  // the browser's fonts. Any call would be a defect, and says so.
  function unused(name) {
    return () => {
      throw new Error(`bikedyn module: ${name} was called; the WebAssembly build draws no figures`);
    };
  }

  function importsOf(module) {
    const imports = {};
    for (const { module: m, name, kind } of WebAssembly.Module.imports(module)) {
      if (kind !== "function") {
        throw new Error(`bikedyn module: unexpected import ${m}.${name} (${kind})`);
      }
      (imports[m] ??= {})[name] = unused(`${m}.${name}`);
    }
    return imports;
  }

  /** A loaded module: `await Bikedyn.load(bytesOrResponse)`. */
  class Bikedyn {
    static async load(source) {
      const module =
        source instanceof WebAssembly.Module
          ? source
          : source && typeof source.arrayBuffer === "function"
            ? await WebAssembly.compile(await source.arrayBuffer())
            : await WebAssembly.compile(source);
      const instance = await WebAssembly.instantiate(module, importsOf(module));
      return new Bikedyn(module, instance);
    }

    constructor(module, instance) {
      this.module = module;
      this.exports = instance.exports;
      this.encoder = new TextEncoder();
      this.decoder = new TextDecoder();
    }

    /** The result of `request` (an object with a `job` field). */
    call(request) {
      const x = this.exports;
      const bytes = this.encoder.encode(JSON.stringify(request));
      const ptr = x.bikedyn_alloc(bytes.length);
      new Uint8Array(x.memory.buffer, ptr, bytes.length).set(bytes);
      let status;
      try {
        status = x.bikedyn_call(ptr, bytes.length);
      } catch (trap) {
        // A panic traps the call; the module's state is then unknown, so a
        // fresh instance replaces it.
        const message = this.decoder.decode(
          new Uint8Array(x.memory.buffer, x.bikedyn_panic_ptr(), x.bikedyn_panic_len()).slice(),
        );
        this.exports = new WebAssembly.Instance(this.module, importsOf(this.module)).exports;
        throw new Error(`bikedyn module: internal error (${message || trap})`);
      }
      x.bikedyn_free(ptr, bytes.length);
      const text = this.decoder.decode(
        new Uint8Array(x.memory.buffer, x.bikedyn_answer_ptr(), x.bikedyn_answer_len()).slice(),
      );
      const answer = JSON.parse(text);
      if (status !== 0) {
        throw new BikedynError(answer.kind, answer.message);
      }
      // Numbers sent as bytes (`eig` with `arrays`): each `[offset, length]`
      // of `arrays` becomes its Float64Array, copied out of the module's
      // memory (the next call reuses it).
      if (answer.arrays && typeof answer.arrays === "object") {
        const base = x.bikedyn_arrays_ptr();
        for (const [name, [offset, length]] of Object.entries(answer.arrays)) {
          answer.arrays[name] = new Float64Array(x.memory.buffer, base + 8 * offset, length).slice();
        }
      }
      return answer;
    }
  }

  // What a worker runs: the factory (bikedyn.js's text, `Bikedyn.workerFactory`)
  // and a loop that answers one request at a time. The first message
  // brings the compiled module, which a worker instantiates with its own
  // memory; a job's error is sent back as its kind and message.
  const WORKER_LOOP = `
    let bikedyn = null;
    self.onmessage = async (event) => {
      const { id, module, request } = event.data;
      try {
        if (module) {
          bikedyn = await api.Bikedyn.load(module);
          self.postMessage({ id, ok: true });
        } else {
          self.postMessage({ id, ok: bikedyn.call(request) });
        }
      } catch (e) {
        self.postMessage({ id, error: { kind: e.kind, message: e.message } });
      }
    };`;

  /**
   * The module in dedicated workers, for long jobs of independent parts
   * (the stability map's rows): `await BikedynWorkers.start(module, count)`,
   * then `call(request)` resolves with the answer or rejects with the
   * BikedynError, each request going to the least busy worker. Rejects if
   * the environment gives no workers (the caller then works in the page).
   */
  class BikedynWorkers {
    static async start(module, count) {
      if (typeof Worker === "undefined" || typeof Blob === "undefined") throw new Error("no Web Workers here");
      const text = `"use strict";\nconst api = (${Bikedyn.workerFactory})();\n${WORKER_LOOP}`;
      const url = URL.createObjectURL(new Blob([text], { type: "text/javascript" }));
      const pool = new BikedynWorkers();
      try {
        for (let k = 0; k < count; k += 1) pool.workers.push(new Worker(url));
        await Promise.all(pool.workers.map((w) => pool.send(w, { module })));
      } catch (e) {
        pool.terminate();
        throw e;
      } finally {
        URL.revokeObjectURL(url);
      }
      for (const w of pool.workers) pool.busy.set(w, 0);
      return pool;
    }

    constructor() {
      this.workers = [];
      this.busy = new Map(); // worker -> requests sent and not yet answered
      this.queue = []; // [request, resolve, reject, group] waiting for a worker
      this.nextId = 1;
    }

    get size() {
      return this.workers.length;
    }

    /** One message to one worker, answered by its reply (or its failure to load). */
    send(worker, message) {
      const id = this.nextId++;
      return new Promise((resolve, reject) => {
        const done = () => {
          worker.removeEventListener("message", onMessage);
          worker.removeEventListener("error", onError);
        };
        const onMessage = (event) => {
          if (event.data.id !== id) return;
          done();
          const { ok, error } = event.data;
          if (error) reject(new BikedynError(error.kind, error.message));
          else resolve(ok);
        };
        const onError = (event) => {
          done();
          event.preventDefault();
          reject(new Error(`bikedyn worker: ${event.message || "failed to start"}`));
        };
        worker.addEventListener("message", onMessage);
        worker.addEventListener("error", onError);
        worker.postMessage(Object.assign({ id }, message));
      });
    }

    /** The answer to `request`, from the least busy worker; `group` names it for `drop`. */
    call(request, group = null) {
      return new Promise((resolve, reject) => {
        this.queue.push([request, resolve, reject, group]);
        this.dispatch();
      });
    }

    // Each worker holds up to four requests: the one it computes and the
    // next ones, so that it does not wait for the page (busy drawing, say)
    // to hear its answer before it gets more work. With one at a time the
    // two workers of a 100 x 100 map took 1.7-1.8 s in Chromium, with four
    // 1.2-1.6 s, against 0.8-1.0 s for the same rows asked of a pool with
    // nothing else to do (2026-11-30).
    dispatch() {
      while (this.queue.length) {
        let worker = null;
        for (const [w, n] of this.busy) if (n < 4 && (!worker || n < this.busy.get(worker))) worker = w;
        if (!worker) return;
        const [request, resolve, reject] = this.queue.shift();
        this.busy.set(worker, this.busy.get(worker) + 1);
        this.send(worker, { request })
          .then(resolve, reject)
          .finally(() => {
            if (this.busy.has(worker)) this.busy.set(worker, this.busy.get(worker) - 1);
            this.dispatch();
          });
      }
    }

    /** The requests of `group` not yet sent to a worker are dropped (their promises never settle). */
    drop(group) {
      this.queue = this.queue.filter((q) => q[3] !== group);
    }

    terminate() {
      for (const w of this.workers) w.terminate();
      this.workers = [];
      this.busy.clear();
      this.queue = [];
    }
  }

  /** The module's bytes from base64 (build.sh's `bikedyn-wasm.js`). */
  function bikedynBytesFromBase64(text) {
    if (typeof Buffer !== "undefined") return new Uint8Array(Buffer.from(text, "base64"));
    const binary = atob(text);
    const bytes = new Uint8Array(binary.length);
    for (let i = 0; i < binary.length; i += 1) bytes[i] = binary.charCodeAt(i);
    return bytes;
  }

  return { Bikedyn, BikedynError, BikedynWorkers, bikedynBytesFromBase64 };
});
