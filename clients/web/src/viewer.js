// The 3D view: a three.js scene with any number of surfaces (each a session's mesh, shaded from
// both sides with the server's normals, an optional wireframe over it), the view box outline,
// axes with ticks and labels, an optional grid on the xy-plane, and orbit/zoom/pan controls.
// z points up, as in GeoGebra 3D. Frames are drawn on demand: when the camera moves or a mesh
// changes, at most once per animation frame.

import {
  AmbientLight,
  Box3,
  Box3Helper,
  Color,
  DirectionalLight,
  Mesh,
  MeshBasicMaterial,
  PerspectiveCamera,
  Scene,
  Vector3,
  WebGLRenderer,
} from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

import { Axes } from './axes.js';
import { SlotGeometry } from './slot_geometry.js';
import { COLOR_MODE_INDEX, sharedSurfaceUniforms, surfaceMaterial } from './surface_material.js';

export const LIGHT_THEME = { background: '#ffffff', axis: '#4b5563', grid: '#c9ced6', label: '#374151', box: '#9aa0a6', wire: '#202830' };
export const DARK_THEME = { background: '#15181d', axis: '#aeb6c2', grid: '#3a414b', label: '#d5dae1', box: '#5f6670', wire: '#e6edf3' };
/** The field of view (degrees) of the view's narrower side. */
const FIELD_OF_VIEW = 40;

/** One surface in the scene: its geometry (over a slot table), shaded mesh and wireframe. */
class SurfaceView {
  constructor(viewer, color) {
    this.viewer = viewer;
    this.slotGeometry = new SlotGeometry();
    const geometry = this.slotGeometry.geometry;
    this.mesh = new Mesh(geometry, surfaceMaterial(color, viewer.uniforms));
    this.wire = new Mesh(geometry, viewer.wireMaterial);
    this.wire.visible = viewer.wireframe;
    for (const mesh of [this.mesh, this.wire]) {
      mesh.frustumCulled = false; // the bounding sphere changes with every delta
      viewer.scene.add(mesh);
    }
    this.visible = true;
  }

  /** Shows the triangles of a TriangleSlots table (null: none). */
  showSlots(slots) {
    if (slots) this.slotGeometry.attach(slots);
    else this.slotGeometry.detach();
    this.viewer.requestRender();
  }

  setColor(color) {
    this.mesh.material.color.set(color);
    this.viewer.requestRender();
  }

  setVisible(on) {
    this.visible = on;
    this.mesh.visible = on;
    this.wire.visible = on && this.viewer.wireframe;
    this.viewer.requestRender();
  }

  dispose() {
    this.viewer.scene.remove(this.mesh, this.wire);
    this.mesh.material.dispose();
    this.slotGeometry.geometry.dispose();
    this.viewer.surfaces.delete(this);
    this.viewer.requestRender();
  }
}

export class Viewer {
  /**
   * @param {HTMLElement} container the element the canvas fills
   * @param {{beforeRender?: () => boolean}} hooks beforeRender runs once per animation frame and
   *   returns true when the scene changed (e.g. new mesh data was synced)
   */
  constructor(container, hooks = {}) {
    this.container = container;
    this.hooks = hooks;
    this.renderer = new WebGLRenderer({ antialias: true, preserveDrawingBuffer: false });
    this.renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
    container.appendChild(this.renderer.domElement);

    this.scene = new Scene();
    this.camera = new PerspectiveCamera(FIELD_OF_VIEW, 1, 0.01, 1000);
    this.camera.up.set(0, 0, 1);
    this.camera.add(new DirectionalLight(0xffffff, 2.4)); // a headlight: every view is lit
    this.camera.children[0].position.set(-0.4, 0.7, 1); // from above left of the eye
    this.scene.add(this.camera, new AmbientLight(0xffffff, 0.55));

    this.uniforms = sharedSurfaceUniforms();
    this.wireframe = false;
    this.wireMaterial = new MeshBasicMaterial({ color: 0x202830, wireframe: true, transparent: true, opacity: 0.35 });
    this.surfaces = new Set();
    this.boxHelper = new Box3Helper(new Box3(), new Color(0x9aa0a6));
    this.axes = new Axes();
    this.scene.add(this.boxHelper, this.axes.group);
    this.setTheme(LIGHT_THEME);

    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.enableDamping = true;
    /** Called (no arguments) whenever the camera moved (orbit, zoom, pan, damping, reset). */
    this.onCameraChange = null;
    this.controls.addEventListener('change', () => {
      this.#updateClipping();
      this.requestRender();
      this.onCameraChange?.();
    });

    this.frames = 0;
    this.renderRequested = true;
    this.resizeObserver = new ResizeObserver(() => this.#resize());
    this.resizeObserver.observe(container);
    this.#resize();
    this.renderer.setAnimationLoop(() => this.#tick());
  }

  /** A new surface in `color` (CSS); returns its handle (showSlots, setColor, setVisible, dispose). */
  addSurface(color) {
    const view = new SurfaceView(this, color);
    this.surfaces.add(view);
    return view;
  }

  setWireframe(on) {
    this.wireframe = on;
    for (const s of this.surfaces) s.wire.visible = on && s.visible;
    this.requestRender();
  }

  /** 'uniform' | 'height' | 'normal' (see surface_material.js). */
  setColorMode(mode) {
    this.uniforms.colorMode.value = COLOR_MODE_INDEX[mode] ?? 0;
    this.requestRender();
  }

  /** Which helpers are drawn: {axes, grid, box} booleans. */
  setShown({ axes, grid, box }) {
    if (axes !== undefined) this.axes.setAxesVisible(axes);
    if (grid !== undefined) this.axes.setGridVisible(grid);
    if (box !== undefined) this.boxHelper.visible = box;
    this.requestRender();
  }

  /** Colours of the background and helpers: LIGHT_THEME or DARK_THEME. */
  setTheme(theme) {
    this.renderer.setClearColor(new Color(theme.background), 1);
    this.boxHelper.material.color.set(theme.box);
    this.wireMaterial.color.set(theme.wire);
    this.axes.setTheme({ axis: theme.axis, grid: theme.grid, label: theme.label });
    this.requestRender();
  }

  /**
   * The view box [x0, x1, y0, y1, z0, z1]: outline, axes, grid, height colours. `frame`: aim the
   * camera at it, from the front-right (true) or from where the camera looks now ('keep').
   */
  setBox(box, { frame = false } = {}) {
    const min = new Vector3(box[0], box[2], box[4]);
    const max = new Vector3(box[1], box[3], box[5]);
    this.boxHelper.box.set(min, max);
    this.axes.setBox(box);
    this.uniforms.zRange.value = [box[4], box[5]];
    if (frame) this.frameBox({ keepDirection: frame === 'keep' });
    this.requestRender();
  }

  /**
   * Looks at the box from the front-right, above (or, with `keepDirection`, from the side the
   * camera is on now), at a distance that shows all of it: the box's bounding sphere fits the
   * field of view of the view's narrower side (FIELD_OF_VIEW, see #resize).
   */
  frameBox({ keepDirection = false } = {}) {
    const box = this.boxHelper.box;
    const center = box.getCenter(new Vector3());
    const radius = box.getSize(new Vector3()).length() / 2;
    const distance = radius / Math.sin((FIELD_OF_VIEW * Math.PI) / 360);
    const current = this.camera.position.clone().sub(this.controls.target);
    const direction = keepDirection && current.lengthSq() > 0 ? current.normalize() : new Vector3(1.2, 0.9, 0.75).normalize();
    this.setCamera({ position: center.clone().addScaledVector(direction, distance).toArray(), target: center.toArray() });
  }

  /** {position, target} of the camera, for the URL. */
  getCamera() {
    return { position: this.camera.position.toArray(), target: this.controls.target.toArray() };
  }

  setCamera({ position, target }) {
    this.camera.position.set(...position);
    this.controls.target.set(...target);
    this.#updateClipping();
    this.controls.update();
    this.requestRender();
  }

  requestRender() {
    this.renderRequested = true;
  }

  /** A PNG of the view as shown (drawn now, read before the browser clears the drawing buffer). */
  toPng() {
    this.#render();
    return new Promise((resolve, reject) =>
      this.renderer.domElement.toBlob((blob) => (blob ? resolve(blob) : reject(new Error('the canvas gave no PNG'))), 'image/png'),
    );
  }

  /** Stops drawing and frees the GPU resources (the element was removed from the page). */
  dispose() {
    this.renderer.setAnimationLoop(null);
    this.resizeObserver.disconnect();
    this.controls.dispose();
    for (const s of [...this.surfaces]) s.dispose();
    this.renderer.dispose();
    this.renderer.domElement.remove();
  }

  #tick() {
    const hooked = this.hooks.beforeRender?.() ?? false;
    let changed = hooked;
    for (const s of this.surfaces) changed = s.slotGeometry.sync() || changed;
    const moving = this.controls.update();
    if (changed || moving || this.renderRequested) this.#render();
  }

  #render() {
    this.renderRequested = false;
    this.renderer.render(this.scene, this.camera);
    ++this.frames;
  }

  /** Near and far planes that follow the zoom: the box is never clipped, depth stays precise. */
  #updateClipping() {
    const distance = this.camera.position.distanceTo(this.controls.target);
    const size = this.boxHelper.box.isEmpty() ? distance : this.boxHelper.box.getSize(new Vector3()).length();
    this.camera.near = Math.max(distance / 100, 1e-6);
    this.camera.far = 10 * distance + 4 * size;
    this.camera.updateProjectionMatrix();
  }

  #resize() {
    const { clientWidth: width, clientHeight: height } = this.container;
    if (width === 0 || height === 0) return;
    this.renderer.setSize(width, height, false);
    // The narrower side sees FIELD_OF_VIEW: a portrait view (a phone with the panel hidden)
    // widens its vertical angle rather than cropping the sides of what a landscape one shows.
    const aspect = width / height;
    const halfTangent = Math.tan((FIELD_OF_VIEW * Math.PI) / 360) / Math.min(1, aspect);
    this.camera.aspect = aspect;
    this.camera.fov = (360 / Math.PI) * Math.atan(halfTangent);
    this.camera.updateProjectionMatrix();
    this.axes.setScreen(height, this.camera.fov);
    this.requestRender();
  }
}
