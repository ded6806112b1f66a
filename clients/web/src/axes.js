// Axes as GeoGebra 3D draws them: x, y and z through the origin (clamped into the view box when
// the origin is outside it), spanning the box, with ticks at round steps (1, 2 or 5 times a power
// of ten), numbers at the ticks and the axis names at the positive ends; and an optional grid on
// the xy-plane at the same steps. Labels are sprites in the scene, so a PNG export shows them;
// they keep their size on screen (13 px numbers, 18 px names) however far the camera is.

import {
  BufferGeometry,
  CanvasTexture,
  Float32BufferAttribute,
  Group,
  LineBasicMaterial,
  LineSegments,
  LinearFilter,
  Sprite,
  SpriteMaterial,
  SRGBColorSpace,
} from 'three';

/** A round step (1, 2 or 5 × 10^k) that cuts `span` into about `target` intervals. */
export function niceStep(span, target = 6) {
  if (!(span > 0) || !Number.isFinite(span)) return 1;
  const raw = span / target;
  const power = 10 ** Math.floor(Math.log10(raw));
  const mantissa = raw / power;
  const nice = mantissa < 1.5 ? 1 : mantissa < 3.5 ? 2 : mantissa < 7.5 ? 5 : 10;
  return nice * power;
}

/** The multiples of `step` in [min, max], without floating-point noise (0.30000000000000004). */
export function tickValues(min, max, step) {
  const first = Math.ceil(min / step - 1e-9);
  const last = Math.floor(max / step + 1e-9);
  const digits = Math.max(0, -Math.floor(Math.log10(step)) + 1);
  const values = [];
  for (let k = first; k <= last && values.length < 1000; ++k) values.push(Number((k * step).toFixed(digits)));
  return values;
}

/** A tick's label: as many decimals as the step needs. */
export function formatTick(value, step) {
  const decimals = Math.max(0, -Math.floor(Math.log10(step) + 1e-9));
  return value.toFixed(decimals).replace('-', '−');
}

const FONT_PX = 64; // the labels' texture resolution
const clamp = (v, lo, hi) => Math.min(hi, Math.max(lo, v));

export class Axes {
  constructor() {
    this.group = new Group();
    this.axesGroup = new Group();
    this.gridGroup = new Group();
    this.group.add(this.axesGroup, this.gridGroup);
    this.theme = { axis: '#4b5563', grid: '#c7ccd3', label: '#374151' };
    this.box = [-1, 1, -1, 1, -1, 1];
    this.labels = []; // {sprite, px, aspect}
    this.pixelScale = 0.001; // sprite scale per screen pixel (see setScreen)
  }

  /**
   * The canvas height in pixels and the camera's vertical field of view (degrees): a label of
   * `px` pixels needs a sprite scale of px · 2 tan(fov / 2) / height (sizeAttenuation off).
   */
  setScreen(heightPx, fovDegrees) {
    this.pixelScale = (2 * Math.tan((fovDegrees * Math.PI) / 360)) / Math.max(1, heightPx);
    for (const label of this.labels) this.#scaleLabel(label);
  }

  #scaleLabel({ sprite, px, aspect }) {
    sprite.scale.set(px * this.pixelScale * aspect, px * this.pixelScale, 1);
  }

  setBox(box) {
    this.box = [...box];
    this.#rebuild();
  }

  /** Colours: {axis, grid, label} as CSS colours (dark mode changes them). */
  setTheme(theme) {
    this.theme = { ...this.theme, ...theme };
    this.#rebuild();
  }

  setAxesVisible(on) {
    this.axesGroup.visible = on;
  }

  setGridVisible(on) {
    this.gridGroup.visible = on;
  }

  #rebuild() {
    this.labels = [];
    for (const group of [this.axesGroup, this.gridGroup]) {
      for (const child of [...group.children]) {
        child.geometry?.dispose();
        child.material.map?.dispose();
        child.material.dispose();
        group.remove(child);
      }
    }
    const [x0, x1, y0, y1, z0, z1] = this.box;
    const extent = Math.max(x1 - x0, y1 - y0, z1 - z0);
    const origin = [clamp(0, x0, x1), clamp(0, y0, y1), clamp(0, z0, z1)];
    const ranges = [
      [x0, x1],
      [y0, y1],
      [z0, z1],
    ];
    const step = niceStep(extent);
    const tick = 0.012 * extent;
    const offset = 0.05 * extent;
    const axisLines = [];
    for (let axis = 0; axis < 3; ++axis) {
      const [lo, hi] = ranges[axis];
      const from = [...origin];
      const to = [...origin];
      from[axis] = lo;
      to[axis] = hi;
      axisLines.push(...from, ...to);
      // Ticks stick out across the axis (x: along y, y: along x, z: along the xy-diagonal that
      // faces the default view), numbers beyond them; none at the crossing or at the far end,
      // where the axis's name is.
      const across = axis === 0 ? [0, 1, 0] : axis === 1 ? [1, 0, 0] : [-Math.SQRT1_2, Math.SQRT1_2, 0];
      for (const value of tickValues(lo, hi, step)) {
        const p = [...origin];
        p[axis] = value;
        axisLines.push(...p.map((c, k) => c - tick * across[k]), ...p.map((c, k) => c + tick * across[k]));
        if (Math.abs(value - origin[axis]) < 1e-9 * extent || Math.abs(value - hi) < 1e-9 * extent) continue;
        const away = axis === 2 ? 1.3 * offset : -1.4 * offset;
        const at = p.map((c, k) => c + away * across[k]);
        if (axis !== 2) at[2] -= 0.5 * offset;
        this.axesGroup.add(this.#label(formatTick(value, step), at, 13));
      }
      const end = [...origin];
      end[axis] = hi + 0.9 * offset;
      this.axesGroup.add(this.#label(['x', 'y', 'z'][axis], end, 18, true));
    }
    this.axesGroup.add(this.#lines(axisLines, this.theme.axis, 1));

    const gridLines = [];
    const z = origin[2];
    for (const x of tickValues(x0, x1, step)) gridLines.push(x, y0, z, x, y1, z);
    for (const y of tickValues(y0, y1, step)) gridLines.push(x0, y, z, x1, y, z);
    this.gridGroup.add(this.#lines(gridLines, this.theme.grid, 0.7));
  }

  #lines(coordinates, color, opacity) {
    const geometry = new BufferGeometry();
    geometry.setAttribute('position', new Float32BufferAttribute(coordinates, 3));
    const material = new LineBasicMaterial({ color, transparent: opacity < 1, opacity });
    return new LineSegments(geometry, material);
  }

  /** A text sprite `px` screen pixels tall, centred on `position`. */
  #label(text, position, px, italic = false) {
    const canvas = document.createElement('canvas');
    const font = `${italic ? 'italic ' : ''}${FONT_PX}px 'DejaVu Sans', system-ui, sans-serif`;
    const context = canvas.getContext('2d');
    context.font = font;
    const width = Math.ceil(context.measureText(text).width) + 8;
    canvas.width = width;
    canvas.height = FONT_PX + 16;
    context.font = font;
    context.fillStyle = this.theme.label;
    context.textAlign = 'center';
    context.textBaseline = 'middle';
    context.fillText(text, width / 2, canvas.height / 2);
    const texture = new CanvasTexture(canvas);
    texture.minFilter = LinearFilter;
    texture.colorSpace = SRGBColorSpace; // the canvas's colours as drawn, not washed out
    const material = new SpriteMaterial({ map: texture, transparent: true, depthWrite: false, sizeAttenuation: false });
    const sprite = new Sprite(material);
    sprite.position.set(...position);
    const label = { sprite, px: (px * canvas.height) / FONT_PX, aspect: width / canvas.height };
    this.labels.push(label);
    this.#scaleLabel(label);
    return sprite;
  }
}
