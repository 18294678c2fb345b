// Validates glTF files with the Khronos glTF validator; exits 1 if any has an error or a warning.
// Usage: node validate_gltf.js FILE.glb... (with gltf-validator installed beside it or on NODE_PATH)
const validator = require("gltf-validator");
const fs = require("fs");

(async () => {
  let failed = false;
  for (const file of process.argv.slice(2)) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)));
    const i = report.issues;
    console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos`);
    for (const m of i.messages) console.log(`  ${m.code} ${m.pointer || ""}: ${m.message}`);
    failed = failed || i.numErrors > 0 || i.numWarnings > 0;
  }
  process.exit(failed ? 1 : 0);
})().catch((e) => {
  console.error(e);
  process.exit(2);
});
