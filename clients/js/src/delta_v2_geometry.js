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
    const { origin } = this.grid;
    return [0, 1, 2].map((axis) => f(f(f(q[axis]) * this.delta) + origin[axis]));
  }

  /** The grid point of a position on the grid. */
  recover(position) {
    const { origin } = this.grid;
    return [0, 1, 2].map((axis) => Math.floor((position[axis] - origin[axis]) / this.delta + 0.5));
  }

  encodeNormal(n) {
    const s = Math.abs(n[0]) + Math.abs(n[1]) + Math.abs(n[2]);
    if (!(s > 0) || !Number.isFinite(s)) return [this.maxOctahedral, 0];
    let x = n[0] / s;
    let y = n[1] / s;
    if (n[2] < 0) [x, y] = [(1 - Math.abs(y)) * sign(x), (1 - Math.abs(x)) * sign(y)];
    const m = this.maxOctahedral;
    return [Math.floor(x * m + 0.5), Math.floor(y * m + 0.5)];
  }

  decodeNormal(code) {
    const m = this.maxOctahedral;
    let x = code[0] / m;
    let y = code[1] / m;
    const z = 1 - Math.abs(x) - Math.abs(y);
    if (z < 0) [x, y] = [(1 - Math.abs(y)) * sign(x), (1 - Math.abs(x)) * sign(y)];
    const length = Math.sqrt(x * x + y * y + z * z);
    return [f(x / length), f(y / length), f(z / length)];
  }

  /** The edge's midpoint bent along its ends' normals by the sagitta of a circular arc. */
  predictSplit(p, q, np, nq) {
    let d = (p[0] - q[0]) * (np[0] - nq[0]);
    d = d + (p[1] - q[1]) * (np[1] - nq[1]);
    d = d + (p[2] - q[2]) * (np[2] - nq[2]);
    d = d / 8;
    return [0, 1, 2].map((axis) => {
      const twice = (p[axis] + q[axis]) + (np[axis] + nq[axis]) * d;
      return Math.min(Math.max(Math.floor(twice * 0.5 + 0.5), 0), this.maxCoordinate);
    });
  }

  predictNormal(np, nq) {
    return this.encodeNormal([np[0] + nq[0], np[1] + nq[1], np[2] + nq[2]]);
  }

  /**
   * A held vertex (grid point p, normal n) moved `steps` grid steps along its normal:
   * p + n * steps, rounded and clamped per axis.
   */
  predictMove(p, n, steps) {
    return [0, 1, 2].map((axis) => Math.min(Math.max(Math.floor(p[axis] + n[axis] * steps + 0.5), 0), this.maxCoordinate));
  }

  validPoint(q) {
    return q.every((c) => c >= 0 && c <= this.maxCoordinate);
  }

  validNormal(n) {
    return n.every((c) => c >= -this.maxOctahedral && c <= this.maxOctahedral);
  }
}

function sign(x) {
  return x >= 0 ? 1 : -1;
}
