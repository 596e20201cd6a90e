// Validates glTF files with the Khronos glTF-Validator (npm gltf-validator, installed by scripts/deps.sh
// into .deps/viewer): exits 1 when a file has an error or a warning, printing them.
// Usage: node validate_gltf.js NODE_MODULES FILE...
const fs = require('fs');
const path = require('path');
const validator = require(path.resolve(process.argv[2], 'gltf-validator'));
(async () => {
  let bad = 0;
  for (const file of process.argv.slice(3)) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), { maxIssues: 100 });
    const { numErrors, numWarnings, messages } = report.issues;
    console.log(`${file}: ${numErrors} errors, ${numWarnings} warnings, ${report.info.animationCount} animation(s), ` +
                `${report.info.totalVertexCount} vertices, morph targets ${report.info.hasMorphTargets}`);
    for (const m of messages.filter((m) => m.severity <= 1)) console.log(`  ${m.code} at ${m.pointer}: ${m.message}`);
    if (numErrors + numWarnings > 0) bad += 1;
  }
  process.exit(bad ? 1 : 0);
})().catch((e) => { console.error(e); process.exit(1); });
