#!/usr/bin/env node
// Validates one .gltf file (and the .bin and images it names) with the Khronos glTF-Validator and
// prints its report as JSON. Exit 0 when the report has no errors and no warnings, 1 when it has,
// 2 when the file cannot be read. Usage: node tools/gltf/validate.js FILE.gltf [--report OUT.json]
'use strict';
const fs = require('fs');
const path = require('path');
const validator = require('gltf-validator');

function main(argv) {
  const file = argv[2];
  if (!file) {
    console.error('usage: validate.js FILE.gltf [--report OUT.json]');
    return Promise.resolve(2);
  }
  const reportIndex = argv.indexOf('--report');
  const reportPath = reportIndex > 0 ? argv[reportIndex + 1] : null;
  let asset;
  try {
    asset = fs.readFileSync(file);
  } catch (error) {
    console.error(`${file}: ${error.message}`);
    return Promise.resolve(2);
  }
  const folder = path.dirname(path.resolve(file));
  return validator
    .validateBytes(new Uint8Array(asset), {
      uri: path.basename(file),
      format: 'gltf',
      maxIssues: 100,
      // External buffers and textures are loaded so that their contents are validated too.
      externalResourceFunction: (uri) =>
        new Promise((resolve, reject) => {
          fs.readFile(path.resolve(folder, decodeURIComponent(uri)), (error, data) =>
            error ? reject(error.toString()) : resolve(new Uint8Array(data)));
        }),
    })
    .then((report) => {
      const text = JSON.stringify(report, null, 2);
      if (reportPath) fs.writeFileSync(reportPath, text);
      console.log(text);
      const issues = report.issues;
      console.error(`${file}: ${issues.numErrors} errors, ${issues.numWarnings} warnings, ` +
                    `${issues.numInfos} infos, ${issues.numHints} hints (validator ${report.validatorVersion})`);
      return issues.numErrors === 0 && issues.numWarnings === 0 ? 0 : 1;
    });
}

main(process.argv).then(
  (code) => process.exit(code),
  (error) => {
    console.error(`${process.argv[2]}: validator failed: ${error}`);
    process.exit(2);
  });
