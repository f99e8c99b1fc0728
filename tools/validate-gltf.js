#!/usr/bin/env node
// Validates .glb/.gltf files with the Khronos glTF validator. Prints one line per file:
//   <path>: errors=N warnings=N
// and exits 1 when any file has an error (or cannot be read), 0 otherwise.
'use strict';
const fs = require('fs');
const path = require('path');
const validator = require('gltf-validator');

async function validateOne(file) {
  const data = new Uint8Array(fs.readFileSync(file));
  const report = await validator.validateBytes(data, {
    uri: path.basename(file),
    maxIssues: 100,
    externalResourceFunction: (uri) => new Promise((resolve, reject) => {
      const p = path.resolve(path.dirname(file), decodeURIComponent(uri));
      fs.readFile(p, (err, d) => err ? reject(err.toString()) : resolve(new Uint8Array(d)));
    }),
  });
  const n = report.issues;
  console.log(`${file}: errors=${n.numErrors} warnings=${n.numWarnings}`);
  for (const m of n.messages) {
    if (m.severity === 0) console.log(`  error ${m.code} ${m.pointer || ''}: ${m.message}`);
  }
  return n.numErrors;
}

(async () => {
  const files = process.argv.slice(2);
  if (files.length === 0) { console.error('usage: validate-gltf.js FILE...'); process.exit(2); }
  let bad = 0;
  for (const f of files) {
    try { if (await validateOne(f) > 0) bad++; }
    catch (e) { console.log(`${f}: cannot validate: ${e}`); bad++; }
  }
  process.exit(bad ? 1 : 0);
})();
