// What the browser tests share: start `sightline serve ... --addr 127.0.0.1:0` and learn
// its URL from the line it prints ("... on http://127.0.0.1:PORT/").
import { spawn } from 'node:child_process';

export function startServer(bin, args, { log = () => {}, timeoutMs = 120_000, echoStderr = false } = {}) {
  log(bin, args.join(' '));
  const proc = spawn(bin, args, { stdio: ['ignore', 'pipe', 'pipe'] });
  let stderr = '';
  proc.stderr.on('data', (d) => {
    stderr += d;
    if (echoStderr) process.stderr.write(d);
  });
  const url = new Promise((res, rej) => {
    let out = '';
    proc.stdout.on('data', (d) => {
      out += d;
      const m = out.match(/on (http:\/\/[^\s]+\/)/);
      if (m) res(m[1]);
    });
    proc.on('exit', (code) => rej(new Error(`server exited (${code}) before listening: ${stderr.trim()}`)));
    setTimeout(() => rej(new Error(`server did not start within ${timeoutMs / 1000} s`)), timeoutMs);
  });
  return { proc, url };
}
