// The 3D view: a three.js scene with the session's mesh (two-sided shading with the server's
// normals, an optional wireframe over it), the view box, axes, and orbit/zoom/pan controls.
// z points up, as in GeoGebra 3D. Frames are drawn on demand: when the camera moves or the mesh
// changes, at most once per animation frame.

import {
  AmbientLight,
  AxesHelper,
  Box3,
  Box3Helper,
  Color,
  DirectionalLight,
  DoubleSide,
  Mesh,
  MeshBasicMaterial,
  MeshPhongMaterial,
  PerspectiveCamera,
  Scene,
  Vector3,
  WebGLRenderer,
} from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

import { SlotGeometry } from './slot_geometry.js';

const FRONT_COLOR = 0x3d7fd6;
const BACK_COLOR = 0xd98c3d;

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
    this.renderer.setClearColor(0xffffff, 1);
    container.appendChild(this.renderer.domElement);

    this.scene = new Scene();
    this.camera = new PerspectiveCamera(40, 1, 0.01, 1000);
    this.camera.up.set(0, 0, 1);
    this.camera.add(new DirectionalLight(0xffffff, 2.6)); // a headlight: every view is lit
    this.camera.children[0].position.set(-0.4, 0.7, 1); // from above left of the eye
    this.scene.add(this.camera, new AmbientLight(0xffffff, 0.45));

    this.slotGeometry = new SlotGeometry();
    this.#addSurface();
    this.boxHelper = new Box3Helper(new Box3(), new Color(0x9aa0a6));
    this.axes = new AxesHelper(1);
    this.scene.add(this.boxHelper, this.axes);

    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.enableDamping = true;
    this.controls.addEventListener('change', () => this.requestRender());

    this.frames = 0;
    this.renderRequested = true;
    new ResizeObserver(() => this.#resize()).observe(container);
    this.#resize();
    this.renderer.setAnimationLoop(() => this.#tick());
  }

  /**
   * The surface in one pass, both sides lit (DoubleSide flips the normal of back faces), back
   * faces in their own color so the inside of an open surface reads as such; then the optional
   * wireframe, drawn over it (the surface is pushed back by a polygon offset).
   */
  #addSurface() {
    const geometry = this.slotGeometry.geometry;
    const material = new MeshPhongMaterial({
      color: FRONT_COLOR,
      side: DoubleSide,
      shininess: 40,
      polygonOffset: true,
      polygonOffsetFactor: 1,
      polygonOffsetUnits: 1,
    });
    material.onBeforeCompile = (shader) => {
      shader.uniforms.backColor = { value: new Color(BACK_COLOR) };
      shader.fragmentShader = shader.fragmentShader
        .replace('void main() {', 'uniform vec3 backColor;\nvoid main() {')
        .replace('vec4 diffuseColor = vec4( diffuse, opacity );', 'vec4 diffuseColor = vec4( gl_FrontFacing ? diffuse : backColor, opacity );');
    };
    this.surface = new Mesh(geometry, material);
    this.wire = new Mesh(geometry, new MeshBasicMaterial({ color: 0x202830, wireframe: true, transparent: true, opacity: 0.35 }));
    this.wire.visible = false;
    for (const mesh of [this.surface, this.wire]) {
      mesh.frustumCulled = false; // the bounding sphere changes with every delta
      this.scene.add(mesh);
    }
  }

  /** Shows the triangles of a TriangleSlots table. */
  showSlots(slots) {
    this.slotGeometry.attach(slots);
    this.requestRender();
  }

  setWireframe(on) {
    this.wire.visible = on;
    this.requestRender();
  }

  setBoxVisible(on) {
    this.boxHelper.visible = on;
    this.axes.visible = on;
    this.requestRender();
  }

  /** The view box [x0, x1, y0, y1, z0, z1]: drawn as an outline; `frame` also aims the camera at it. */
  setBox(box, { frame = false } = {}) {
    const min = new Vector3(box[0], box[2], box[4]);
    const max = new Vector3(box[1], box[3], box[5]);
    this.boxHelper.box.set(min, max);
    const size = max.clone().sub(min);
    this.axes.scale.setScalar(0.6 * Math.max(size.x, size.y, size.z));
    if (frame) this.frameBox();
    this.requestRender();
  }

  /** Looks at the box from the front-right, above, at a distance that shows all of it. */
  frameBox() {
    const box = this.boxHelper.box;
    const center = box.getCenter(new Vector3());
    const radius = box.getSize(new Vector3()).length() / 2;
    const distance = radius / Math.sin((this.camera.fov * Math.PI) / 360);
    const direction = new Vector3(1.2, 0.9, 0.75).normalize();
    this.camera.position.copy(center).addScaledVector(direction, distance);
    this.camera.near = distance / 100;
    this.camera.far = distance * 10;
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(center);
    this.controls.update();
    this.requestRender();
  }

  requestRender() {
    this.renderRequested = true;
  }

  #tick() {
    const hooked = this.hooks.beforeRender?.() ?? false;
    const changed = this.slotGeometry.sync() || hooked;
    const moving = this.controls.update();
    if (changed || moving || this.renderRequested) {
      this.renderRequested = false;
      this.renderer.render(this.scene, this.camera);
      ++this.frames;
    }
  }

  #resize() {
    const { clientWidth: width, clientHeight: height } = this.container;
    if (width === 0 || height === 0) return;
    this.renderer.setSize(width, height, false);
    this.camera.aspect = width / height;
    this.camera.updateProjectionMatrix();
    this.requestRender();
  }
}
