// Export of what is shown, from the browser: the visible surfaces as they are held (the triangles
// drawn, indexed by the server's vertex ids so that the files are connected meshes), written by
// three.js's exporters.
//
//   .glb  glTF 2.0 binary: one node per surface with its colour, double-sided. glTF is y-up, so the
//         surfaces hang under a root node that turns the equation's z-up coordinates to y-up.
//   .stl  binary STL, every surface in one solid, in the equation's coordinates (z up).
//   .obj  Wavefront OBJ, one object per surface (named by its equation), z up.
//   .png  a screenshot of the view (Viewer.toPng).

import { BufferAttribute, BufferGeometry, DoubleSide, Group, Mesh, MeshStandardMaterial } from 'three';
import { GLTFExporter } from 'three/addons/exporters/GLTFExporter.js';
import { OBJExporter } from 'three/addons/exporters/OBJExporter.js';
import { STLExporter } from 'three/addons/exporters/STLExporter.js';

/** Unit normals (glTF requires them): a zero normal (a degenerate spot) becomes +z. */
export function unitNormals(normals) {
  const out = new Float32Array(normals.length);
  for (let i = 0; i < normals.length; i += 3) {
    const [x, y, z] = [normals[i], normals[i + 1], normals[i + 2]];
    const length = Math.hypot(x, y, z);
    if (length > 1e-12 && Number.isFinite(length)) {
      out[i] = x / length;
      out[i + 1] = y / length;
      out[i + 2] = z / length;
    } else {
      out[i + 2] = 1;
    }
  }
  return out;
}

/**
 * A three.js Group of meshes in the equation's coordinates, from
 * [{name, color, positions, normals, indices}] (SessionMesh.toIndexed() plus a name and colour).
 */
export function exportGroup(surfaces) {
  const group = new Group();
  group.name = 'isomesh';
  for (const s of surfaces) {
    if (s.indices.length === 0) continue;
    const geometry = new BufferGeometry();
    geometry.setAttribute('position', new BufferAttribute(s.positions, 3));
    geometry.setAttribute('normal', new BufferAttribute(unitNormals(s.normals), 3));
    geometry.setIndex(new BufferAttribute(s.indices, 1));
    const material = new MeshStandardMaterial({ color: s.color, side: DoubleSide, roughness: 0.6, metalness: 0 });
    material.name = s.name;
    const mesh = new Mesh(geometry, material);
    mesh.name = s.name;
    group.add(mesh);
  }
  group.updateMatrixWorld(true);
  return group;
}

/** The .glb bytes (an ArrayBuffer). */
export async function toGlb(surfaces) {
  const root = new Group();
  root.name = 'z-up';
  root.rotation.x = -Math.PI / 2; // (x, y, z) -> (x, z, -y): the equation's z becomes glTF's up
  root.add(exportGroup(surfaces));
  return new GLTFExporter().parseAsync(root, { binary: true, onlyVisible: false });
}

/** The binary .stl bytes (an ArrayBuffer). */
export function toStl(surfaces) {
  const view = new STLExporter().parse(exportGroup(surfaces), { binary: true });
  return view.buffer.slice(view.byteOffset, view.byteOffset + view.byteLength);
}

/** The .obj text. */
export function toObj(surfaces) {
  return `# isomesh: ${surfaces.map((s) => s.name).join('; ')}\n${new OBJExporter().parse(exportGroup(surfaces))}`;
}

/** Saves `data` (a Blob, ArrayBuffer or string) as a download named `filename`. */
export function download(data, filename, type) {
  const blob = data instanceof Blob ? data : new Blob([data], { type });
  const url = URL.createObjectURL(blob);
  const a = document.createElement('a');
  a.href = url;
  a.download = filename;
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10000);
}
