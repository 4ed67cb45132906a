// The glTF files a check script walks: every .glb/.gltf directly in the
// directory given as the script's first argument, sorted so reports are
// stable. Shared by check_gltf.mjs and check_gltf_consumer.mjs.
//
// Exits 2 without an argument, and 1 if the directory holds no glTF file
// at all (a silently empty run proves nothing).

import fs from "node:fs";

export function gltfFilesFromArguments(tool) {
  const directory = process.argv[2];
  if (!directory) {
    console.error(`usage: node ${tool}.mjs DIR`);
    process.exit(2);
  }
  const files = fs
    .readdirSync(directory)
    .filter((name) => /\.(glb|gltf)$/i.test(name))
    .sort();
  if (files.length === 0) {
    console.error(`${tool}: no .glb or .gltf file in ${directory}`);
    process.exit(1);
  }
  return { directory, files };
}
