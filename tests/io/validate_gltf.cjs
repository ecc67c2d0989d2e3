// Run the Khronos glTF validator on one file and print its JSON report.
// Usage: node validate_gltf.cjs <path to node_modules/gltf-validator> <file.glb|.gltf>
const fs = require("fs");
const path = require("path");
const validator = require(process.argv[2]);
const file = process.argv[3];
const folder = path.dirname(file);

validator
  .validateBytes(new Uint8Array(fs.readFileSync(file)), {
    uri: path.basename(file),
    maxIssues: 100,
    externalResourceFunction: (uri) =>
      new Promise((resolve, reject) => {
        fs.readFile(path.join(folder, decodeURIComponent(uri)), (err, data) =>
          err ? reject(err.toString()) : resolve(new Uint8Array(data)));
      }),
  })
  .then((report) => console.log(JSON.stringify(report, null, 1)))
  .catch((error) => { console.error(String(error)); process.exit(2); });
