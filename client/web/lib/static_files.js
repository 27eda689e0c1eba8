// Serves the page: GET of files under public/, nothing else. "/" is
// index.html; names are resolved inside the folder (no "..", no dot files).
// A path that does not decode (a lone "%") is 400; nothing a request holds
// throws out of the handler.
import fs from 'node:fs/promises';
import path from 'node:path';

const kTypes = {
  '.html': 'text/html; charset=utf-8',
  '.js': 'text/javascript; charset=utf-8',
  '.css': 'text/css; charset=utf-8',
  '.svg': 'image/svg+xml',
  '.png': 'image/png',
  '.ico': 'image/x-icon',
};

export function staticHandler(root) {
  const base = path.resolve(root);
  return async (req, res) => {
    if (req.method !== 'GET' && req.method !== 'HEAD') {
      res.writeHead(405, { Allow: 'GET, HEAD' }).end('method not allowed\n');
      return;
    }
    let name;
    try {
      const url = new URL(req.url, 'http://gateway');
      name = url.pathname === '/' ? 'index.html' : decodeURIComponent(url.pathname.slice(1));
    } catch {
      res.writeHead(400).end('bad request path\n');
      return;
    }
    const file = path.resolve(base, name);
    const type = kTypes[path.extname(file)];
    if (!file.startsWith(base + path.sep) || name.split('/').some((p) => p.startsWith('.')) ||
        type === undefined) {
      res.writeHead(404).end('not found\n');
      return;
    }
    try {
      const body = await fs.readFile(file);
      res.writeHead(200, { 'Content-Type': type, 'Cache-Control': 'no-cache',
                           'Content-Length': body.length });
      res.end(req.method === 'HEAD' ? undefined : body);
    } catch {
      res.writeHead(404).end('not found\n');
    }
  };
}
