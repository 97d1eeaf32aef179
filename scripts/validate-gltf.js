#!/usr/bin/env node
// Validates a glTF or GLB file with the Khronos glTF Validator (npm package
// `gltf-validator`, scripts/install-node-tools.sh) and prints a one-object
// JSON summary: counts of errors, warnings, infos and hints, and the messages
// (code, severity, pointer) of every issue reported.
//
//   node scripts/validate-gltf.js FILE.glb
//
// Exit 0 when the validator reports no errors, 1 when it reports some or
// cannot read the file, 2 for bad arguments or the package missing.
'use strict';
const fs = require('fs');
const path = require('path');

const { package_root } = require('./node-packages.js');

const file = process.argv[2];
if (!file || process.argv.length !== 3) {
  console.error('usage: validate-gltf.js FILE.glb');
  process.exit(2);
}
const root = package_root('gltf-validator');
if (!root) {
  console.error('validate-gltf: npm package gltf-validator not found (scripts/install-node-tools.sh; set CELLBAKE_NODE_TOOLS)');
  process.exit(2);
}
const validator = require(root);
validator.validateBytes(new Uint8Array(fs.readFileSync(file)), { uri: path.basename(file), maxIssues: 200 })
  .then((report) => {
    const issues = report.issues;
    console.log(JSON.stringify({
      file, validator: report.validatorVersion,
      errors: issues.numErrors, warnings: issues.numWarnings, infos: issues.numInfos, hints: issues.numHints,
      messages: issues.messages.map((m) => ({ code: m.code, severity: m.severity, pointer: m.pointer, message: m.message })),
    }, null, 1));
    process.exit(issues.numErrors === 0 ? 0 : 1);
  }, (error) => {
    console.error('validate-gltf: ' + error);
    process.exit(1);
  });
