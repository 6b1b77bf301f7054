// Runs the Khronos glTF validator (npm gltf-validator, pinned in package-lock.json beside this
// file; scripts/install-deps.sh runs `npm ci` here) on each .glb/.gltf named on the command line.
//   node tests/support/gltf/gltf_validate.mjs FILE...
// Prints each file's errors and warnings (code, JSON pointer, message) and a one-line summary.
// Exit status: 0 when no file has an error, 1 when one has (or cannot be read or parsed), 2 on bad
// usage. Warnings, infos and hints are printed but do not fail. External resources (a .gltf's .bin
// and image URIs) are read relative to the file.
import { readFile } from 'node:fs/promises';
import path from 'node:path';
import validator from 'gltf-validator';

const files = process.argv.slice(2);
if (files.length === 0) {
  console.error('usage: node gltf_validate.mjs FILE.glb|FILE.gltf...');
  process.exit(2);
}

const severities = ['error', 'warning', 'info', 'hint'];
let failed = false;
for (const file of files) {
  let report;
  try {
    const bytes = await readFile(file);
    report = await validator.validateBytes(new Uint8Array(bytes), {
      uri: path.basename(file),
      maxIssues: 0,  // no limit
      externalResourceFunction: (uri) =>
        readFile(path.resolve(path.dirname(file), decodeURIComponent(uri))).then((data) => new Uint8Array(data)),
    });
  } catch (error) {
    console.error(`${file}: cannot validate: ${error}`);
    failed = true;
    continue;
  }
  const issues = report.issues;
  for (const m of issues.messages) {
    if (m.severity > 1) continue;  // infos and hints are summarised only
    console.log(`${file}: ${severities[m.severity]}: ${m.code} at ${m.pointer ?? ''}: ${m.message}`);
  }
  console.log(`${file}: ${issues.numErrors} errors, ${issues.numWarnings} warnings, ${issues.numInfos} infos, ` +
              `${issues.numHints} hints (glTF validator ${report.validatorVersion})`);
  if (issues.numErrors > 0) failed = true;
}
process.exit(failed ? 1 : 0);
