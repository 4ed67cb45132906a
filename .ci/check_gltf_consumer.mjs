// Loads every .glb/.gltf in a directory with a second real glTF consumer,
// glTF Transform (@gltf-transform/core, the library behind gltf.report and
// many pipelines), beside the Khronos validator of check_gltf.mjs. For each
// file it checks what a client would get: every attribute the JSON names
// (TEXCOORD_0 and the custom `_NAME` attributes) is loaded with one element
// per vertex and finite values, custom attributes have 1, 3 or 4
// components and one width within a primitive (Blender 5.0.1's importer
// pairs custom attributes with their data in two different orders, a list
// and a set, so mixed widths fail or swap names), every morph target is loaded with a POSITION per
// vertex, and the animations keep their channels.
//
//   node .ci/check_gltf_consumer.mjs DIR
//
// Exits 1 if any file fails, and if DIR holds no glTF file at all.

import fs from "node:fs";
import path from "node:path";
import { gltfFilesFromArguments } from "./gltf_files.mjs";
import { NodeIO } from "@gltf-transform/core";

const { directory, files } = gltfFilesFromArguments("check_gltf_consumer");

// The JSON part of a file, to compare with what the consumer loaded.
function rawJson(bytes, name) {
  if (!/\.glb$/i.test(name)) {
    return JSON.parse(bytes.toString("utf8"));
  }
  const length = bytes.readUInt32LE(12);
  return JSON.parse(bytes.subarray(20, 20 + length).toString("utf8"));
}

const io = new NodeIO();
let failed = 0;
for (const name of files) {
  const full = path.join(directory, name);
  const problems = [];
  let document;
  let json;
  try {
    const bytes = fs.readFileSync(full);
    json = rawJson(bytes, name);
    document = await io.read(full);
  } catch (error) {
    console.log(`${name}: glTF Transform could not load it: ${error}`);
    failed += 1;
    continue;
  }
  const root = document.getRoot();
  let attributes = 0;
  let targets = 0;
  const meshes = root.listMeshes();
  if (meshes.length !== (json.meshes ?? []).length) {
    problems.push(`${meshes.length} meshes loaded, the JSON has ${(json.meshes ?? []).length}`);
  }
  meshes.forEach((mesh, m) => {
    mesh.listPrimitives().forEach((primitive, p) => {
      const where = `mesh ${m} primitive ${p}`;
      const rawPrimitive = json.meshes?.[m]?.primitives?.[p] ?? {};
      const position = primitive.getAttribute("POSITION");
      const vertices = position ? position.getCount() : 0;
      if (!position) problems.push(`${where}: no POSITION`);
      for (const semantic of Object.keys(rawPrimitive.attributes ?? {})) {
        const accessor = primitive.getAttribute(semantic);
        if (!accessor) {
          problems.push(`${where}: ${semantic} not loaded`);
          continue;
        }
        attributes += 1;
        const size = accessor.getElementSize();
        if (semantic.startsWith("_") && ![1, 3, 4].includes(size)) {
          problems.push(`${where}: custom attribute ${semantic} has ${size} components`);
        }
        if (semantic === "TEXCOORD_0" && size !== 2) {
          problems.push(`${where}: TEXCOORD_0 has ${size} components`);
        }
        if (accessor.getCount() !== vertices) {
          problems.push(`${where}: ${semantic} has ${accessor.getCount()} elements for ${vertices} vertices`);
        }
        const array = accessor.getArray();
        if (!array || array.length !== accessor.getCount() * size) {
          problems.push(`${where}: ${semantic} data not loaded`);
        } else if (!Array.from(array).every(Number.isFinite)) {
          problems.push(`${where}: ${semantic} has values that are not finite`);
        }
      }
      const widths = new Set(
        Object.keys(rawPrimitive.attributes ?? {})
          .filter((semantic) => semantic.startsWith("_"))
          .map((semantic) => primitive.getAttribute(semantic)?.getElementSize()),
      );
      if (widths.size > 1) {
        problems.push(`${where}: custom attributes of different widths (${[...widths].join(", ")})`);
      }
      const rawTargets = rawPrimitive.targets ?? [];
      const loaded = primitive.listTargets();
      if (loaded.length !== rawTargets.length) {
        problems.push(`${where}: ${loaded.length} morph targets loaded, the JSON has ${rawTargets.length}`);
      }
      loaded.forEach((target, t) => {
        const delta = target.getAttribute("POSITION");
        if (!delta || delta.getCount() !== vertices || delta.getArray().length !== 3 * vertices) {
          problems.push(`${where}: morph target ${t} has no POSITION per vertex`);
        }
        targets += 1;
      });
    });
  });
  const animations = root.listAnimations();
  (json.animations ?? []).forEach((rawAnimation, a) => {
    const channels = animations[a]?.listChannels() ?? [];
    if (channels.length !== rawAnimation.channels.length) {
      problems.push(`animation ${a}: ${channels.length} channels loaded, the JSON has ${rawAnimation.channels.length}`);
    }
    for (const channel of channels) {
      const sampler = channel.getSampler();
      if (!channel.getTargetNode() || !sampler?.getInput() || !sampler?.getOutput()) {
        problems.push(`animation ${a}: a channel lost its node or sampler`);
      }
    }
  });
  console.log(
    `${name}: ${meshes.length} meshes, ${attributes} attributes, ${targets} morph targets,` +
      ` ${animations.length} animations`,
  );
  for (const problem of problems) console.log(`  FAIL ${problem}`);
  if (problems.length > 0) failed += 1;
}
console.log(`check_gltf_consumer: ${files.length} files, ${failed} failed`);
process.exit(failed > 0 ? 1 : 0);
