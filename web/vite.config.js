import { defineConfig } from 'vite';
import fs from 'node:fs';
import path from 'node:path';

// The marker fba-run replaces with the run's messages (docs/live-view.md).
const MARKER = '<!--FBA_REPORT_DATA-->';

// report.html: the built index.html with its script and style inlined, so that a report opens from
// disk, sent to anyone, with no other file. Made after the bundle is written, from those files.
function reportTemplate() {
  let outDir;
  return {
    name: 'fba-report-template',
    apply: 'build',
    configResolved(config) {
      outDir = path.resolve(config.root, config.build.outDir);
    },
    closeBundle() {
      let html = fs.readFileSync(path.join(outDir, 'index.html'), 'utf8');
      const read = (ref) => fs.readFileSync(path.join(outDir, ref.replace(/^\.?\//, '')), 'utf8');
      let scripts = 0;
      html = html.replace(/<script type="module" crossorigin src="([^"]+)"><\/script>\s*/g, (_, src) => {
        scripts++;
        // Inside a script element, only "</script" and "<!--" could end or confuse it: written so
        // that they mean the same to JavaScript but not to HTML.
        const js = read(src).replace(/<\/(script)/gi, '<\\/$1').replace(/<!--/g, '<\\!--');
        return `${MARKER}\n<script type="module">${js}</script>\n`;
      });
      html = html.replace(/<link rel="stylesheet" crossorigin href="([^"]+)">/g, (_, href) => `<style>${read(href).replace(/<\/(style)/gi, '<\\/$1')}</style>`);
      html = html.replace('<title>fba live view</title>', '<title>fba run report</title>');
      if (scripts !== 1) throw new Error(`report.html: expected one module script in index.html, found ${scripts}`);
      if (/<(script|link)[^>]+(src|href)="(?!data:)/.test(html)) throw new Error('report.html still refers to another file');
      const markers = html.split(MARKER).length - 1;
      if (markers !== 1) throw new Error(`report.html must hold the marker ${MARKER} exactly once, not ${markers} times`);
      fs.writeFileSync(path.join(outDir, 'report.html'), html);
    },
  };
}

export default defineConfig({
  base: './',
  build: {
    outDir: process.env.FBA_WEB_OUT_DIR || 'dist',
    emptyOutDir: true,
    target: 'es2020',
    chunkSizeWarningLimit: 4096,
    // One script, no chunks loaded later: report.html inlines it whole.
    rollupOptions: { output: { inlineDynamicImports: true } },
    assetsInlineLimit: 1 << 20,
    reportCompressedSize: false,
  },
  plugins: [reportTemplate()],
});
