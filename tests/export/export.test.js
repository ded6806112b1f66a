// The files `isomesh mesh -o FILE` writes, read by other people's software: the .glb passes
// Khronos's glTF validator with no errors and its KHR_draco_mesh_compression payload, decoded by
// Google's draco3d, holds the triangles of the .ply of the same mesh; the binary .stl has them too.
//
// ISOMESH_BIN overrides the CLI (default: build/bin/isomesh of this checkout).

import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { after, before, describe, test } from 'node:test';
import assert from 'node:assert/strict';
import { fileURLToPath } from 'node:url';

import draco3d from 'draco3d';
import validator from 'gltf-validator';

const REPO = fileURLToPath(new URL('../..', import.meta.url));
const ISOMESH = process.env.ISOMESH_BIN ?? join(REPO, 'build/bin/isomesh');

const SURFACES = [
  { name: 'bumpy sphere (thesis)', args: ['x^2+y^2+z^2+2cos(2x)=5', '--box', '-3,3,-3,3,-3,3'] },
  {
    name: 'bumpy sphere refined to 20,000 triangles',
    args: ['x^2+y^2+z^2+2cos(2x)=5', '--box', '-3,3,-3,3,-3,3', '--triangles', '20000'],
  },
  { name: 'torus', args: ['(sqrt(x^2+y^2)-2)^2+z^2=0.49', '--box', '-3.2,3.2,-3.2,3.2,-1.2,1.2'] },
  { name: 'open gyroid patch', args: ['sin(x)cos(y)+sin(y)cos(z)+sin(z)cos(x)=0', '--box', '-3,3,-3,3,-3,3'] },
];

let scratch;
let draco;
before(async () => {
  scratch = mkdtempSync(join(tmpdir(), 'isomesh-export-'));
  draco = await draco3d.createDecoderModule({});
});
after(() => rmSync(scratch, { recursive: true, force: true }));

function mesh(args, file) {
  const path = join(scratch, file);
  execFileSync(ISOMESH, ['mesh', ...args, '-o', path], { stdio: ['ignore', 'ignore', 'pipe'] });
  return readFileSync(path);
}

/** Vertex and face counts and the bounding box of a binary little-endian PLY from mesh_io. */
function readPly(bytes) {
  const end = bytes.indexOf('end_header\n');
  assert.ok(end > 0, 'PLY header');
  const header = bytes.subarray(0, end).toString('latin1');
  const count = (element) => Number(header.match(new RegExp(`element ${element} (\\d+)`))[1]);
  const vertices = count('vertex');
  const faces = count('face');
  const stride = (header.match(/property float/g).length) * 4;
  const body = new DataView(bytes.buffer, bytes.byteOffset + end + 'end_header\n'.length);
  const min = [Infinity, Infinity, Infinity];
  const max = [-Infinity, -Infinity, -Infinity];
  for (let v = 0; v < vertices; ++v) {
    for (let axis = 0; axis < 3; ++axis) {
      const x = body.getFloat32(v * stride + axis * 4, true);
      min[axis] = Math.min(min[axis], x);
      max[axis] = Math.max(max[axis], x);
    }
  }
  return { vertices, faces, min, max };
}

/** The JSON and BIN chunks of a GLB (glTF 2.0 binary container). */
function readGlb(bytes) {
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  assert.equal(bytes.subarray(0, 4).toString('latin1'), 'glTF');
  assert.equal(view.getUint32(4, true), 2, 'GLB version');
  assert.equal(view.getUint32(8, true), bytes.length, 'GLB length');
  const chunks = {};
  for (let offset = 12; offset < bytes.length;) {
    const length = view.getUint32(offset, true);
    const type = bytes.subarray(offset + 4, offset + 8).toString('latin1').replace(/\0/g, '');
    chunks[type] = bytes.subarray(offset + 8, offset + 8 + length);
    offset += 8 + length;
  }
  return { json: JSON.parse(chunks.JSON.toString('utf8')), bin: chunks.BIN };
}

/** Decodes a Draco mesh: face count, positions and normals (3 floats per point). */
function decodeDraco(bytes, attributeIds) {
  const decoder = new draco.Decoder();
  const buffer = new draco.DecoderBuffer();
  buffer.Init(new Int8Array(bytes.buffer, bytes.byteOffset, bytes.byteLength), bytes.byteLength);
  const dracoMesh = new draco.Mesh();
  const status = decoder.DecodeBufferToMesh(buffer, dracoMesh);
  assert.ok(status.ok(), `draco3d: ${status.error_msg()}`);
  const points = dracoMesh.num_points();
  const floats = (uniqueId) => {
    const attribute = decoder.GetAttributeByUniqueId(dracoMesh, uniqueId);
    assert.ok(attribute.ptr !== 0, `attribute ${uniqueId}`);
    const bytesNeeded = points * 12;
    const ptr = draco._malloc(bytesNeeded);
    decoder.GetAttributeDataArrayForAllPoints(dracoMesh, attribute, draco.DT_FLOAT32, bytesNeeded, ptr);
    const out = new Float32Array(draco.HEAPF32.buffer, ptr, points * 3).slice();
    draco._free(ptr);
    return out;
  };
  const result = {
    faces: dracoMesh.num_faces(),
    points,
    positions: floats(attributeIds.POSITION),
    normals: floats(attributeIds.NORMAL),
  };
  draco.destroy(dracoMesh);
  draco.destroy(buffer);
  draco.destroy(decoder);
  return result;
}

describe('isomesh mesh -o FILE.glb', () => {
  for (const surface of SURFACES) {
    test(`${surface.name}: valid glTF, Draco payload with the .ply's triangles`, async () => {
      const ply = readPly(mesh(surface.args, 'mesh.ply'));
      assert.ok(ply.faces > 100, `a real mesh (${ply.faces} triangles)`);
      const glbBytes = mesh(surface.args, 'mesh.glb');

      const report = await validator.validateBytes(new Uint8Array(glbBytes));
      const errors = report.issues.messages.filter((m) => m.severity === 0);
      assert.equal(report.issues.numErrors, 0, JSON.stringify(errors, null, 1));

      const { json, bin } = readGlb(glbBytes);
      assert.ok(json.extensionsRequired.includes('KHR_draco_mesh_compression'));
      const primitive = json.meshes[0].primitives[0];
      assert.equal(primitive.mode ?? 4, 4, 'triangles');
      assert.ok('NORMAL' in primitive.attributes, 'normals included');
      assert.equal(json.accessors[primitive.indices].count, 3 * ply.faces);
      const extension = primitive.extensions.KHR_draco_mesh_compression;
      const bufferView = json.bufferViews[extension.bufferView];
      const payload = bin.subarray(bufferView.byteOffset ?? 0, (bufferView.byteOffset ?? 0) + bufferView.byteLength);

      const decoded = decodeDraco(payload, extension.attributes);
      assert.equal(decoded.faces, ply.faces, 'triangle count of the Draco payload');
      assert.equal(json.accessors[primitive.attributes.POSITION].count, decoded.points);
      for (let p = 0; p < decoded.points; ++p) {
        const n = decoded.normals.subarray(3 * p, 3 * p + 3);
        assert.ok(Math.abs(Math.hypot(n[0], n[1], n[2]) - 1) < 1e-3, `unit normal at point ${p}`);
      }
      const position = json.accessors[primitive.attributes.POSITION];
      for (let axis = 0; axis < 3; ++axis) {
        const extent = ply.max[axis] - ply.min[axis];
        assert.ok(Math.abs(position.min[axis] - ply.min[axis]) <= 1e-4 * extent, `min[${axis}]`);
        assert.ok(Math.abs(position.max[axis] - ply.max[axis]) <= 1e-4 * extent, `max[${axis}]`);
      }
    });
  }
});

describe('isomesh mesh -o FILE.stl', () => {
  test('binary STL with the .ply\'s triangles and unit facet normals', () => {
    const { args } = SURFACES[0];
    const ply = readPly(mesh(args, 'mesh.ply'));
    const stl = mesh(args, 'mesh.stl');
    const view = new DataView(stl.buffer, stl.byteOffset, stl.byteLength);
    const count = view.getUint32(80, true);
    assert.equal(count, ply.faces);
    assert.equal(stl.length, 84 + 50 * count);
    for (let t = 0; t < count; t += 97) {
      const at = 84 + 50 * t;
      const n = [0, 1, 2].map((i) => view.getFloat32(at + 4 * i, true));
      assert.ok(Math.abs(Math.hypot(...n) - 1) < 1e-3, `facet normal ${t}`);
    }
  });
});
