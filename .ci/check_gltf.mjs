// Validates every .glb/.gltf in a directory with the Khronos glTF-Validator
// and checks the `<file>.expect.json` sidecars the integration tests write
// (see tests/integration/util.rs `hand_to_validators`).
//
//   node .ci/check_gltf.mjs DIR
//
// Exits 1 if any file has an error or a warning, breaks an expectation, or
// if DIR holds no glTF file at all (a silently empty run proves nothing).
// Sidecar keys: kind ("gltf"), primitives (draw calls), vertices (total
// vertex count), animations (animation count), morph_targets (bool).

import fs from "node:fs";
import path from "node:path";
import { gltfFilesFromArguments } from "./gltf_files.mjs";
import validator from "gltf-validator";

const { directory, files } = gltfFilesFromArguments("check_gltf");

// Expectation key -> how to read it from the validator's report.
const checks = {
  kind: () => "gltf",
  primitives: (info) => info.drawCallCount,
  vertices: (info) => info.totalVertexCount,
  animations: (info) => info.animationCount,
  morph_targets: (info) => info.hasMorphTargets,
};

let failed = 0;
for (const name of files) {
  const full = path.join(directory, name);
  const problems = [];
  let report;
  try {
    report = await validator.validateBytes(new Uint8Array(fs.readFileSync(full)), {
      uri: name,
      maxIssues: 0,
      externalResourceFunction: (uri) =>
        new Promise((resolve, reject) => {
          const resource = path.resolve(directory, decodeURIComponent(uri));
          fs.readFile(resource, (error, data) => (error ? reject(error.toString()) : resolve(data)));
        }),
    });
  } catch (error) {
    console.log(`${name}: the validator could not read it: ${error}`);
    failed += 1;
    continue;
  }
  const { numErrors, numWarnings, numInfos, numHints } = report.issues;
  // A file the validator cannot parse (e.g. a truncated GLB) has no info.
  const info = report.info ?? {};
  console.log(
    `${name}: ${numErrors} errors, ${numWarnings} warnings, ${numInfos} infos, ${numHints} hints` +
      ` (${info.drawCallCount} primitives, ${info.totalVertexCount} vertices,` +
      ` ${info.animationCount} animations)`,
  );
  const severities = ["error", "warning", "info", "hint"];
  for (const message of report.issues.messages) {
    console.log(`  ${severities[message.severity]} ${message.code} ${message.pointer ?? ""} ${message.message}`);
  }
  if (numErrors > 0 || numWarnings > 0) {
    problems.push("errors or warnings");
  }
  const sidecar = `${full}.expect.json`;
  if (fs.existsSync(sidecar)) {
    const expected = JSON.parse(fs.readFileSync(sidecar, "utf8"));
    for (const [key, want] of Object.entries(expected)) {
      const read = checks[key];
      if (!read) {
        problems.push(`unknown expectation key '${key}'`);
        continue;
      }
      const got = read(info);
      if (got !== want) {
        problems.push(`${key}: expected ${JSON.stringify(want)}, found ${JSON.stringify(got)}`);
      }
    }
  }
  for (const problem of problems) {
    console.log(`  FAIL ${problem}`);
  }
  if (problems.length > 0) {
    failed += 1;
  }
}
console.log(`check_gltf: ${files.length} files, ${failed} failed`);
process.exit(failed > 0 ? 1 : 0);
