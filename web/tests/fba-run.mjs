// A real fba-run for the browser tests: started with --serve 0, its page's address read from the
// line it prints on stderr, stopped with a signal (SIGINT unless told) when a test is done with it. Arguments given to a
// test: --fba-run PATH (the program) --source-dir DIR (the checkout: tasks/ and data/).
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';

export function testArguments() {
  const args = process.argv.slice(2);
  const value = (name) => {
    const i = args.indexOf(name);
    if (i < 0 || i + 1 >= args.length) throw new Error(`usage: node ${path.basename(process.argv[1])} --fba-run PATH --source-dir DIR`);
    return args[i + 1];
  };
  return { fbaRun: path.resolve(value('--fba-run')), sourceDir: path.resolve(value('--source-dir')) };
}

// A temporary folder for one test, removed when it passes (kept, and named, when it fails).
export function temporaryFolder(name) {
  return fs.mkdtempSync(path.join(os.tmpdir(), `fba-web-${name}-`));
}

const URL_LINE = /^fba-run: live view at (http:\/\/\S+)$/m;

export class FbaRun {
  constructor(program, args, { cwd }) {
    this.stderr = '';
    this.stdout = '';
    this.child = spawn(program, args, { cwd, stdio: ['ignore', 'pipe', 'pipe'] });
    this.child.stdout.on('data', (d) => { this.stdout += d; });
    this.exited = new Promise((resolve) => {
      this.child.on('exit', (code, signal) => resolve({ code, signal }));
    });
    this.url = new Promise((resolve, reject) => {
      this.child.stderr.on('data', (d) => {
        this.stderr += d;
        const m = URL_LINE.exec(this.stderr);
        if (m) resolve(m[1]);
      });
      this.child.on('error', reject);
      this.exited.then(({ code, signal }) => reject(new Error(
        `fba-run exited (${code ?? signal}) before printing its live view's address; its stderr:\n${this.stderr}`)));
    });
  }

  get running() {
    return this.child.exitCode === null && this.child.signalCode === null;
  }

  // Resolves when fba-run has said `text` on stderr; rejects when it exits without saying it.
  said(text) {
    return new Promise((resolve, reject) => {
      const look = () => {
        if (this.stderr.includes(text)) resolve();
        else if (!this.running) reject(new Error(`fba-run exited without saying "${text}"; its stderr:\n${this.stderr}`));
        else setTimeout(look, 100);
      };
      look();
    });
  }

  async stop(signal = 'SIGINT') {
    if (this.running) this.child.kill(signal);
    return this.exited;
  }
}
