// The mesh a client holds for one session, as version-2 deltas need it (a port of
// protocol/held_mesh.cpp): triangles by id, vertices by global id (position and normal as float32
// values), and each vertex's star (the triangles using it). A delta names held triangles and
// predicts new vertices from held ones (PROTOCOL.md 4.5).

export class HeldMesh {
  constructor() {
    this.triangles = new Map(); // id -> [a, b, c]
    this.vertices = new Map(); // global id -> {position: [x, y, z], normal: [x, y, z]}
    this.stars = new Map(); // global id -> triangle ids
  }

  triangle(id) {
    return this.triangles.get(id);
  }

  vertex(id) {
    return this.vertices.get(id);
  }

  star(id) {
    return this.stars.get(id) ?? [];
  }

  clear() {
    this.triangles.clear();
    this.vertices.clear();
    this.stars.clear();
  }

  /**
   * Applies a decoded frame ({header, removed, triangleIds, mesh}, as decodeFrame or decodeDeltaV2
   * return it) in the order of PROTOCOL.md 6.2; vertices no triangle uses are dropped.
   */
  apply(frame) {
    if (frame.header.kind === 'keyframe') this.clear();
    for (const id of frame.removed) this.#remove(id);
    const { mesh, triangleIds } = frame;
    if (!mesh) return;
    const { globalIds, positions, normals, faces, values } = mesh;
    for (let p = 0; p < globalIds.length; ++p) {
      // values: the {position, normal} objects decodeDeltaV2 made (the same numbers).
      this.vertices.set(globalIds[p], values?.[p] ?? {
        position: [positions[3 * p], positions[3 * p + 1], positions[3 * p + 2]],
        normal: [normals[3 * p], normals[3 * p + 1], normals[3 * p + 2]],
      });
    }
    for (let t = 0; t < triangleIds.length; ++t) {
      this.#add(triangleIds[t], [globalIds[faces[3 * t]], globalIds[faces[3 * t + 1]], globalIds[faces[3 * t + 2]]]);
    }
    for (const id of globalIds) {
      if (!this.stars.has(id)) this.vertices.delete(id);
    }
  }

  #remove(id) {
    const corners = this.triangles.get(id);
    if (!corners) return;
    for (const v of corners) {
      const star = this.stars.get(v);
      star.splice(star.indexOf(id), 1);
      if (star.length === 0) {
        this.stars.delete(v);
        this.vertices.delete(v);
      }
    }
    this.triangles.delete(id);
  }

  #add(id, corners) {
    this.triangles.set(id, corners);
    for (const v of corners) {
      const star = this.stars.get(v);
      if (star) star.push(id);
      else this.stars.set(v, [id]);
    }
  }
}
