const fs = require('fs');
const validator = require('gltf-validator');
const path = process.argv[2];
const data = new Uint8Array(fs.readFileSync(path));
validator.validateBytes(data, { uri: path, externalResourceFunction: (u) => Promise.reject('no external') })
  .then((r) => { console.log(JSON.stringify({errors: r.issues.numErrors, warnings: r.issues.numWarnings, messages: r.issues.messages.slice(0, 10)}, null, 1)); process.exit(r.issues.numErrors > 0 ? 1 : 0); })
  .catch((e) => { console.error(e); process.exit(2); });
