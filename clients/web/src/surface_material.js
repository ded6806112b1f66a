// The surfaces' material: Phong shading lit from both sides, coloured one of three ways (the
// user's choice, shared by every surface):
//   uniform  the surface's own colour (its row in the object list)
//   height   a colour ramp over z, from the bottom of the view box to its top (as Desmos 3D)
//   normal   the direction the surface faces: (r, g, b) = (1 + n) / 2 of its unit normal
// The side seen from f < 0 is the same colour a shade darker: an open surface reads as one sheet
// with two sides, not as two colours (an orange inside looked like a rendering defect).

import { Color, DoubleSide, MeshPhongMaterial } from 'three';

export const COLOR_MODE_INDEX = { uniform: 0, height: 1, normal: 2 };
const BACK_SHADE = 0.78;

/** Uniforms shared by every surface's material: changing one recolours them all. */
export function sharedSurfaceUniforms() {
  return {
    colorMode: { value: 0 },
    zRange: { value: [-1, 1] },
  };
}

const VERTEX_DECLARATIONS = 'varying vec3 vObjectPosition;\nvarying vec3 vObjectNormal;\n';
const FRAGMENT_DECLARATIONS = `uniform int colorMode;
uniform vec2 zRange;
varying vec3 vObjectPosition;
varying vec3 vObjectNormal;
vec3 heightRamp(float t) {
  t = clamp(t, 0.0, 1.0);
  vec3 c0 = vec3(0.19, 0.32, 0.74), c1 = vec3(0.13, 0.62, 0.70), c2 = vec3(0.40, 0.76, 0.35);
  vec3 c3 = vec3(0.96, 0.78, 0.25), c4 = vec3(0.86, 0.33, 0.24);
  if (t < 0.25) return mix(c0, c1, t * 4.0);
  if (t < 0.5) return mix(c1, c2, t * 4.0 - 1.0);
  if (t < 0.75) return mix(c2, c3, t * 4.0 - 2.0);
  return mix(c3, c4, t * 4.0 - 3.0);
}
`;
const BASE_COLOR = `vec3 base = diffuse;
  // The ramp and the normal colours are sRGB values; shading works in linear light.
  if (colorMode == 1) base = pow(heightRamp((vObjectPosition.z - zRange.x) / max(zRange.y - zRange.x, 1e-9)), vec3(2.2));
  else if (colorMode == 2) base = pow(0.5 + 0.5 * normalize(vObjectNormal + vec3(1e-9)), vec3(2.2));
  if (!gl_FrontFacing) base *= ${BACK_SHADE};
  vec4 diffuseColor = vec4( base, opacity );`;

/** A surface's material in `color`, using the shared `uniforms`. */
export function surfaceMaterial(color, uniforms) {
  const material = new MeshPhongMaterial({
    color: new Color(color),
    side: DoubleSide,
    shininess: 30,
    specular: new Color(0x222222),
    polygonOffset: true, // the wireframe is drawn over the surface
    polygonOffsetFactor: 1,
    polygonOffsetUnits: 1,
  });
  material.onBeforeCompile = (shader) => {
    shader.uniforms.colorMode = uniforms.colorMode;
    shader.uniforms.zRange = uniforms.zRange;
    shader.vertexShader = shader.vertexShader
      .replace('void main() {', `${VERTEX_DECLARATIONS}void main() {`)
      .replace('#include <begin_vertex>', '#include <begin_vertex>\n  vObjectPosition = position;\n  vObjectNormal = normal;');
    shader.fragmentShader = shader.fragmentShader
      .replace('void main() {', `${FRAGMENT_DECLARATIONS}void main() {`)
      .replace('vec4 diffuseColor = vec4( diffuse, opacity );', BASE_COLOR);
  };
  material.customProgramCacheKey = () => 'isomesh-surface';
  return material;
}
