// Runs a wasm32-wasip1 program under Node's WASI (Node >= 20) and exits with its status.
// Usage: node --no-warnings run.mjs path/to/program.wasm [ARGS...] (the program's arguments)
import { readFile } from 'node:fs/promises';
import { argv, exit } from 'node:process';
import { WASI } from 'node:wasi';

const path = argv[2];
if (!path) {
  console.error('usage: node run.mjs PROGRAM.wasm');
  exit(2);
}
const wasi = new WASI({ version: 'preview1', args: [path, ...argv.slice(3)], env: {}, returnOnExit: true });
const module = await WebAssembly.compile(await readFile(path));
const instance = await WebAssembly.instantiate(module, wasi.getImportObject());
exit(wasi.start(instance));
