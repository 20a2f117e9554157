// Runs a wasm32-wasip1 test binary under Node's WASI, as cargo's runner for that target:
// `CARGO_TARGET_WASM32_WASIP1_RUNNER="node web/test/wasi-run.mjs"`. Exits with its code.
import { readFile } from 'node:fs/promises';
import { argv, env, exit } from 'node:process';
import { WASI } from 'node:wasi';

const [file, ...args] = argv.slice(2);
const wasi = new WASI({ version: 'preview1', args: [file, ...args], env, returnOnExit: true });
const module = await WebAssembly.compile(await readFile(file));
const instance = await WebAssembly.instantiate(module, wasi.getImportObject());
exit(wasi.start(instance));
