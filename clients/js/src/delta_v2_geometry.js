// Grid, octahedral normals and split predictions of version-2 frames (PROTOCOL.md 4.5.3), a port
// of protocol/delta_v2_geometry.cpp: IEEE-754 double operations in the C++ order, Math.fround
// where the C++ rounds to float, so both compute the same integers.

const f = Math.fround;

export class GridMath {
  /** @param {{origin: number[], range: number, positionBits: number, normalBits: number}} grid */
  constructor(grid) {
    this.grid = grid;
    this.maxCoordinate = 2 ** grid.positionBits - 1;
    this.maxOctahedral = 2 ** (grid.normalBits - 1) - 1;
    this.delta = f(grid.range / f(this.maxCoordinate));
  }

  /** Draco's dequantization, in float: float(float(float(q) * delta) + origin). */
  dequantize(q) {
    const out = [0, 0, 0];
    this.dequantizeInto(q, 0, out, 0);
    return out;
  }

  dequantizeInto(q, at, out, to) {
    const { origin } = this.grid;
    for (let axis = 0; axis < 3; ++axis) out[to + axis] = f(f(f(q[at + axis]) * this.delta) + origin[axis]);
  }

  /** The grid point of a position on the grid. */
  recover(position) {
    const out = [0, 0, 0];
    this.recoverInto(position, 0, out, 0);
    return out;
  }

  recoverInto(position, at, out, to) {
    const { origin } = this.grid;
    for (let axis = 0; axis < 3; ++axis) out[to + axis] = Math.floor((position[at + axis] - origin[axis]) / this.delta + 0.5);
  }

  encodeNormal(n) {
    const out = [0, 0];
    this.encodeNormalInto(n[0], n[1], n[2], out, 0);
    return out;
  }

  encodeNormalInto(nx, ny, nz, out, to) {
    const m = this.maxOctahedral;
    const s = Math.abs(nx) + Math.abs(ny) + Math.abs(nz);
    if (!(s > 0) || !Number.isFinite(s)) {
      out[to] = m;
      out[to + 1] = 0;
      return;
    }
    let x = nx / s;
    let y = ny / s;
    if (nz < 0) {
      const folded = (1 - Math.abs(y)) * sign(x);
      y = (1 - Math.abs(x)) * sign(y);
      x = folded;
    }
    out[to] = Math.floor(x * m + 0.5);
    out[to + 1] = Math.floor(y * m + 0.5);
  }

  decodeNormal(code) {
    const out = [0, 0, 0];
    this.decodeNormalInto(code[0], code[1], out, 0);
    return out;
  }

  decodeNormalInto(u, v, out, to) {
    const m = this.maxOctahedral;
    let x = u / m;
    let y = v / m;
    const z = 1 - Math.abs(x) - Math.abs(y);
    if (z < 0) {
      const folded = (1 - Math.abs(y)) * sign(x);
      y = (1 - Math.abs(x)) * sign(y);
      x = folded;
    }
    const length = Math.sqrt(x * x + y * y + z * z);
    out[to] = f(x / length);
    out[to + 1] = f(y / length);
    out[to + 2] = f(z / length);
  }

  /** The edge's midpoint bent along its ends' normals by the sagitta of a circular arc. */
  predictSplit(p, q, np, nq) {
    const out = [0, 0, 0];
    this.predictSplitInto(p, 0, q, 0, np, 0, nq, 0, out);
    return out;
  }

  /** predictSplit on grid points p[pa..pa+3), q[qa..), normals np[na..), nq[nb..), into out[0..3). */
  predictSplitInto(p, pa, q, qa, np, na, nq, nb, out) {
    let d = (p[pa] - q[qa]) * (np[na] - nq[nb]);
    d = d + (p[pa + 1] - q[qa + 1]) * (np[na + 1] - nq[nb + 1]);
    d = d + (p[pa + 2] - q[qa + 2]) * (np[na + 2] - nq[nb + 2]);
    d = d / 8;
    for (let axis = 0; axis < 3; ++axis) {
      const twice = (p[pa + axis] + q[qa + axis]) + (np[na + axis] + nq[nb + axis]) * d;
      out[axis] = Math.min(Math.max(Math.floor(twice * 0.5 + 0.5), 0), this.maxCoordinate);
    }
  }

  predictNormal(np, nq) {
    return this.encodeNormal([np[0] + nq[0], np[1] + nq[1], np[2] + nq[2]]);
  }

  /**
   * The grid point p moved `steps` grid steps along the normal at normals[at..at+2]:
   * p + n * steps, rounded and clamped per axis (in place).
   */
  predictMoveInto(p, normals, at, steps) {
    for (let axis = 0; axis < 3; ++axis) {
      const moved = Math.floor(p[axis] + normals[at + axis] * steps + 0.5);
      p[axis] = Math.min(Math.max(moved, 0), this.maxCoordinate);
    }
  }

  validPoint(q) {
    const m = this.maxCoordinate;
    return q[0] >= 0 && q[0] <= m && q[1] >= 0 && q[1] <= m && q[2] >= 0 && q[2] <= m;
  }

  validNormal(n) {
    return this.validNormalCode(n[0], n[1]);
  }

  validNormalCode(u, v) {
    const m = this.maxOctahedral;
    return u >= -m && u <= m && v >= -m && v <= m;
  }
}

function sign(x) {
  return x >= 0 ? 1 : -1;
}
