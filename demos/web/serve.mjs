// A tiny static file server for the page (Node >= 18, no packages): serves this
// directory on 127.0.0.1 and prints `serving http://127.0.0.1:<port>/`.
// The page in test mode POSTs its outcome (`<scene> <steps> <checksum> <ms>` or
// `error: ...`, one short line) to /result; the server prints it as `result <line>`, which
// is what test.sh waits for, so no test depends on when Chromium decides a page is done.
// Usage: node serve.mjs [PORT]   (PORT 0: any free port; default 8000)
import { createServer } from "node:http";
import { readFile } from "node:fs/promises";
import { extname, join, normalize, sep } from "node:path";
import { fileURLToPath } from "node:url";

const root = fileURLToPath(new URL(".", import.meta.url));
const port = Number(process.argv[2] ?? process.env.PORT ?? 8000);
const types = {
  ".html": "text/html; charset=utf-8",
  ".js": "text/javascript; charset=utf-8",
  ".wasm": "application/wasm",
  ".png": "image/png",
};

// The longest result line accepted (bytes); longer bodies are cut there.
const MAX_RESULT = 512;

function acceptResult(req, res) {
  let body = "";
  req.setEncoding("utf8");
  req.on("data", (chunk) => {
    if (body.length < MAX_RESULT) body += chunk.slice(0, MAX_RESULT - body.length);
  });
  req.on("end", () => {
    console.log(`result ${body.replace(/[\r\n]+/g, " ").trim()}`);
    res.writeHead(204).end();
  });
}

const server = createServer(async (req, res) => {
  if (req.method === "POST" && req.url === "/result") {
    acceptResult(req, res);
    return;
  }
  const path = decodeURIComponent(new URL(req.url, "http://x").pathname);
  const file = normalize(join(root, path.endsWith("/") ? path + "index.html" : path));
  const type = types[extname(file)];
  if (!file.startsWith(root) || file.includes(`${sep}target${sep}`) || !type) {
    res.writeHead(404).end("not found\n");
    return;
  }
  try {
    const body = await readFile(file);
    res.writeHead(200, {
      "content-type": type,
      "cache-control": "no-store",
      // Cross-origin isolation: performance.now() then ticks in 5 us, not 100 us.
      "cross-origin-opener-policy": "same-origin",
      "cross-origin-embedder-policy": "require-corp",
    }).end(body);
  } catch {
    res.writeHead(404).end("not found\n");
  }
});
server.listen(port, "127.0.0.1", () => {
  console.log(`serving http://127.0.0.1:${server.address().port}/`);
});
