// Starts build/bin/isomesh-server on a free loopback port for a test and stops it afterwards.
//
// The server is started with --port 0 and reports the port it got in its "listening" log line
// (one JSON object per line on stderr). ISOMESH_SERVER_BIN and ISOMESH_WEB_ROOT override the
// binary and the browser client's folder.

import { spawn } from 'node:child_process';
import { existsSync } from 'node:fs';
import { join } from 'node:path';
import { createInterface } from 'node:readline';
import { fileURLToPath } from 'node:url';

export const REPO = fileURLToPath(new URL('../..', import.meta.url));
export const SERVER_BIN = process.env.ISOMESH_SERVER_BIN ?? join(REPO, 'build/bin/isomesh-server');
export const WEB_ROOT = process.env.ISOMESH_WEB_ROOT ?? join(REPO, 'build/web');

/**
 * Resolves with {url, port, stop(), kill(), log} once the server listens (kill: SIGKILL, no drain).
 * `log` collects its log lines.
 * Rejects if it exits or stays silent for `timeoutMs`.
 */
export function startServer(extraArgs = [], { timeoutMs = 20000 } = {}) {
  for (const [what, path] of [['server binary', SERVER_BIN], ['web client (build/web/index.html)', join(WEB_ROOT, 'index.html')]]) {
    if (!existsSync(path)) throw new Error(`no ${what} at ${path}: run scripts/build.sh first`);
  }
  // Defaults that extraArgs do not name (sessions in memory only unless a --store is given).
  const defaults = ['--bind', '127.0.0.1', '--port', '0', '--web-root', WEB_ROOT, '--threads', '2', '--store', 'none'];
  const args = [];
  for (let i = 0; i < defaults.length; i += 2) {
    if (!extraArgs.includes(defaults[i])) args.push(defaults[i], defaults[i + 1]);
  }
  args.push(...extraArgs);
  const child = spawn(SERVER_BIN, args, { stdio: ['ignore', 'pipe', 'pipe'] });
  const log = [];
  let onLine = () => {};
  for (const stream of [child.stdout, child.stderr]) {
    createInterface({ input: stream }).on('line', (line) => {
      log.push(line);
      onLine(line);
    });
  }
  const exited = new Promise((resolve) => child.once('exit', (code, signal) => resolve({ code, signal })));

  const kill = async () => {
    if (child.exitCode === null && child.signalCode === null) child.kill('SIGKILL');
    return exited;
  };

  const stop = async () => {
    if (child.exitCode === null && child.signalCode === null) child.kill('SIGTERM');
    const timer = setTimeout(() => child.kill('SIGKILL'), 10000);
    const result = await exited;
    clearTimeout(timer);
    return result;
  };

  return new Promise((resolve, reject) => {
    const timer = setTimeout(() => {
      stop();
      reject(new Error(`isomesh-server reported no port within ${timeoutMs} ms; log:\n${log.join('\n')}`));
    }, timeoutMs);
    exited.then(({ code, signal }) => {
      clearTimeout(timer);
      reject(new Error(`isomesh-server exited (${code ?? signal}); log:\n${log.join('\n')}`));
    });
    onLine = (line) => {
      const port = listeningPort(line);
      if (port === null) return;
      clearTimeout(timer);
      onLine = () => {};
      resolve({ port, url: `http://127.0.0.1:${port}/`, stop, kill, log });
    };
  });
}

/** The port of a {"event":"listening","port":N,...} log line, or null. */
function listeningPort(line) {
  let entry;
  try {
    entry = JSON.parse(line);
  } catch {
    return null;
  }
  const listening = typeof entry?.event === 'string' && entry.event.includes('listen');
  return listening && Number.isInteger(entry.port) && entry.port > 0 ? entry.port : null;
}
