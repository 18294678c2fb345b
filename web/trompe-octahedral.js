// trompe's octahedral impostors in three.js: loads a `.glb` that `trompe impostor bake MESH
// --octahedral N -o NAME.glb` wrote and draws it as an engine draws a distant object — a
// camera-facing card per instance whose fragments blend the three atlas frames around the view
// direction, each lookup parallax-corrected with the frame's depth, keep what has coverage ≥ ½
// (the alpha test), light the blended normal and write the depth of the surface found.
//
// The rules are trompe's CPU reference (src/octahedral/render.rs) and its WGSL runtime
// (shaders/octahedral_impostor.wgsl); the file's layout is docs/conventions.md §8: the
// material's `extras.trompe_octahedral` gives the grid, the frame size, the bounding sphere and
// the indices of three embedded textures — colour + coverage (sRGB), normal + depth packed in one
// RGBA texture (linear: rgb = n·½ + ½ in the object's space, a = depth behind the frame's front
// plane over the sphere's diameter) and occlusion-roughness-metalness.
//
// The card is cut to the layout's `card` outline, which holds every view's silhouette, so the
// pixels round the object where no frame can find it are never shaded. Instances carry any
// translation, rotation and uniform scale (an InstancedMesh's matrices, times the mesh's own).
// Mip levels are chosen from each pixel's footprint and kept inside their frame; trompe dilates
// every frame whole so coarse levels never pull in the background. Across the layout's
// `cross_fade` the impostor and the mesh share the pixels by a dithered rule (`crossFade`,
// `crossFadeMaterial`).

import {
  BufferGeometry,
  Float32BufferAttribute,
  GLSL3,
  InstancedMesh,
  NoColorSpace,
  SRGBColorSpace,
  ShaderMaterial,
  Sphere,
  Vector2,
  Vector3,
  Box3,
} from 'three';

/** The `format` of the layout this runtime reads. */
export const FORMAT = 'trompe-octahedral-impostor';

/** The newest layout version this runtime reads. */
export const VERSION = 3;

/**
 * The atlas of a loaded glTF (from three's GLTFLoader): its layout and its three textures.
 * Throws, naming what is missing, when the file is not a trompe octahedral impostor.
 */
export async function readOctahedralAtlas(gltf) {
  const json = gltf.parser.json;
  const material = (json.materials || []).find((m) => m.extras && m.extras.trompe_octahedral);
  if (!material) {
    throw new Error('no material has extras.trompe_octahedral: not an octahedral impostor trompe baked');
  }
  const layout = material.extras.trompe_octahedral;
  if (layout.format !== FORMAT) {
    throw new Error(`extras.trompe_octahedral.format is ${JSON.stringify(layout.format)}, not ${FORMAT}`);
  }
  if (!(layout.version >= 3 && layout.version <= VERSION)) {
    throw new Error(`layout version ${layout.version}: this runtime reads 3 to ${VERSION}`);
  }
  const t = layout.textures;
  const [color, normalDepth, orm] = await Promise.all(
    [t.color, t.normal_depth, t.orm].map((i) => gltf.parser.getDependency('texture', i)),
  );
  color.colorSpace = SRGBColorSpace;
  normalDepth.colorSpace = NoColorSpace;
  orm.colorSpace = NoColorSpace;
  for (const texture of [color, normalDepth, orm]) texture.needsUpdate = true;
  return { layout, color, normalDepth, orm };
}

/** Loads `url` with `loader` (three's GLTFLoader) and returns its atlas. */
export async function loadOctahedralAtlas(url, loader) {
  return readOctahedralAtlas(await loader.loadAsync(url));
}

/**
 * GLSL of the layout's dithered cross-fade (src/octahedral/lod.rs, conventions §8.5): between
 * `uFade.x` and `uFade.y` (distances from the eye to the bounding sphere's centre, the bake's
 * units) the impostor draws a share of the pixels chosen by a 4 × 4 Bayer matrix on
 * gl_FragCoord, the mesh the others; `uFade = (0, 0)` gives every pixel to the impostor.
 */
export const CROSS_FADE_GLSL = `
uniform vec2 uFade;
float lodShare(float distance) {
  if (uFade.y <= uFade.x) return distance >= uFade.x ? 1.0 : 0.0;
  return clamp((distance - uFade.x) / (uFade.y - uFade.x), 0.0, 1.0);
}
bool lodImpostorDraws(vec2 fragCoord, float distance) {
  const float bayer[16] = float[16](0.0, 8.0, 2.0, 10.0, 12.0, 4.0, 14.0, 6.0,
                                    3.0, 11.0, 1.0, 9.0, 15.0, 7.0, 13.0, 5.0);
  ivec2 p = ivec2(floor(fragCoord)) % 4;
  return (bayer[p.y * 4 + p.x] + 0.5) / 16.0 < lodShare(distance);
}
`;

const vertexShader = /* glsl */ `
uniform vec3 uCentre;
uniform float uRadius;
uniform float uNear;

// Object space of this instance: the bake's own space.
flat out mat4 vModel;
flat out vec3 vEye;
out vec3 vObject;

vec3 frameRight(vec3 d) {
  vec3 reference = abs(d.y) > 0.999 ? vec3(0.0, 0.0, -sign(d.y)) : vec3(0.0, 1.0, 0.0);
  return normalize(cross(reference, d));
}

void main() {
  mat4 model = modelMatrix;
#ifdef USE_INSTANCING
  model = model * instanceMatrix;
#endif
  mat4 toObject = inverse(model);
  vec3 eye = (toObject * vec4(cameraPosition, 1.0)).xyz;
  float scale = length(model[0].xyz);
  vec2 corner = position.xy;
  vec3 toEye = eye - uCentre;
  vec3 object;
  if ((length(toEye) - uRadius) * scale > 4.0 * uNear) {
    // A card in front of the sphere, toward the eye, covering its silhouette.
    vec3 d = normalize(toEye);
    vec3 right = frameRight(d);
    vec3 up = cross(d, right);
    object = uCentre + d * uRadius + (right * corner.x + up * corner.y) * uRadius;
  } else {
    // The eye in the sphere or at it: a card across the whole view just past the near plane.
    vec3 forward = -vec3(viewMatrix[0][2], viewMatrix[1][2], viewMatrix[2][2]);
    vec3 right = frameRight(-forward);
    vec3 up = cross(-forward, right);
    float d = 4.0 * uNear;
    // The outline's corners pushed onto the square's edge: wide enough whatever its shape.
    vec2 c = corner / max(max(abs(corner.x), abs(corner.y)), 1e-6);
    vec3 world = cameraPosition + forward * d + (right * c.x + up * c.y) * (100.0 * d);
    object = (toObject * vec4(world, 1.0)).xyz;
  }
  vModel = model;
  vEye = eye;
  vObject = object;
  gl_Position = projectionMatrix * viewMatrix * model * vec4(object, 1.0);
}
`;

const fragmentShader = /* glsl */ `
precision highp float;

layout(location = 0) out highp vec4 pc_fragColor;
#define gl_FragColor pc_fragColor

uniform mat4 projectionMatrix;
uniform sampler2D uColor;
uniform sampler2D uNormalDepth;
uniform vec3 uCentre;
uniform float uRadius;
uniform float uFrames;
uniform float uFrameSize;
uniform int uCoverage;
uniform float uDistance;
uniform float uParallaxSteps;
uniform float uAlphaTest;
uniform float uMaxLod;
uniform vec3 uSunDirection;
uniform vec3 uSunIrradiance;
uniform vec3 uAmbient;
${CROSS_FADE_GLSL}
flat in mat4 vModel;
flat in vec3 vEye;
in vec3 vObject;

const int COVERAGE_SPHERE = 0;
const int COVERAGE_HEMISPHERE = 1;
const float PI = 3.141592653589793;
// The coverage from which a lookup is a surface, and depth-aware blending's tolerance in
// bounding radii (src/octahedral/render.rs: ALPHA_TEST, DEPTH_AGREEMENT).
const float COVERED = 0.5;
const float DEPTH_AGREEMENT = 0.125;

float signNonzero(float v) { return v >= 0.0 ? 1.0 : -1.0; }

// The unit square point of unit direction d (src/octahedral/mapping.rs, encode).
vec2 octEncode(vec3 dir) {
  vec3 d = dir;
  if (uCoverage == COVERAGE_HEMISPHERE) d.y = max(d.y, 0.0);
  d /= max(abs(d.x) + abs(d.y) + abs(d.z), 1e-30);
  vec2 p;
  if (uCoverage == COVERAGE_SPHERE) {
    p = d.y >= 0.0 ? d.xz
      : vec2((1.0 - abs(d.z)) * signNonzero(d.x), (1.0 - abs(d.x)) * signNonzero(d.z));
  } else {
    p = vec2(d.x + d.z, d.z - d.x);
  }
  return clamp(p * 0.5 + 0.5, 0.0, 1.0);
}

// The unit direction of unit square point uv (mapping.rs, decode).
vec3 octDecode(vec2 uv) {
  vec2 p = uv * 2.0 - 1.0;
  vec3 d;
  if (uCoverage == COVERAGE_SPHERE) {
    float y = 1.0 - abs(p.x) - abs(p.y);
    d = y >= 0.0 ? vec3(p.x, y, p.y)
      : vec3((1.0 - abs(p.y)) * signNonzero(p.x), y, (1.0 - abs(p.x)) * signNonzero(p.y));
  } else {
    float x = (p.x - p.y) * 0.5;
    float z = (p.x + p.y) * 0.5;
    d = vec3(x, 1.0 - abs(x) - abs(z), z);
  }
  return normalize(d);
}

vec3 frameDirection(vec2 frame) { return octDecode(frame / (uFrames - 1.0)); }

vec3 frameRight(vec3 d) {
  vec3 reference = abs(d.y) > 0.999 ? vec3(0.0, 0.0, -sign(d.y)) : vec3(0.0, 1.0, 0.0);
  return normalize(cross(reference, d));
}

// Atlas coordinates of frame texel coordinates t (texel centres at +0.5), kept half a texel of
// mip level lod inside the frame.
vec2 atlasUv(vec2 frame, vec2 t, float lod) {
  float margin = 0.5 * exp2(lod);
  vec2 inside = clamp(t, vec2(margin), vec2(uFrameSize - margin));
  return (frame * uFrameSize + inside) / (uFrameSize * uFrames);
}

// Frame texel coordinates of object point p in the frame looking along -d (render.rs,
// frame_texel): orthographic, or through the frame's pinhole.
vec2 frameTexel(vec3 p, vec3 d, vec3 right, vec3 up) {
  vec3 q = p - uCentre;
  float scale = uRadius;
  if (uDistance > 0.0) {
    q = p - (uCentre + d * (uRadius * uDistance));
    float z = max(-dot(q, d), 1e-12 * uRadius);
    scale = z / sqrt(max(uDistance * uDistance - 1.0, 1e-12));
  }
  return vec2((dot(q, right) / scale + 1.0) * 0.5 * uFrameSize,
              (1.0 - dot(q, up) / scale) * 0.5 * uFrameSize);
}

struct Lookup { vec4 color; vec3 normal; vec3 position; float inside; };

// Frame 'frame' along the ray o + t·dir, parallax-corrected (render.rs, lookup).
Lookup lookup(vec2 frame, vec3 o, vec3 dir, float lod) {
  vec3 d = frameDirection(frame);
  vec3 right = frameRight(d);
  vec3 up = cross(d, right);
  float facing = min(dot(dir, d), -1e-6);
  vec3 p = o + dir * (dot(uCentre - o, d) / facing);
  vec2 t = frameTexel(p, d, right, up);
  for (float k = 0.0; k < uParallaxSteps; k += 1.0) {
    float depth = textureLod(uNormalDepth, atlasUv(frame, t, lod), lod).a;
    float offset = uRadius - 2.0 * uRadius * depth;
    p = o + dir * (dot(uCentre + d * offset - o, d) / facing);
    t = frameTexel(p, d, right, up);
  }
  Lookup out_;
  vec2 uv = atlasUv(frame, t, lod);
  out_.color = textureLod(uColor, uv, lod);
  out_.normal = textureLod(uNormalDepth, uv, lod).rgb * 2.0 - 1.0;
  out_.position = p;
  out_.inside = all(greaterThanEqual(t, vec2(-1.0))) && all(lessThanEqual(t, vec2(uFrameSize + 1.0))) ? 1.0 : 0.0;
  return out_;
}

void main() {
  // The mip level of this pixel's footprint on the card (before any branch): a bilinear tap
  // of level L spans 2^(L+1) texels, so a footprint of w texels takes level log2(w) - 1.
  float footprint = max(length(dFdx(vObject)), length(dFdy(vObject)));
  float lod = clamp(log2(footprint * uFrameSize / (2.0 * uRadius)) - 1.0, 0.0, uMaxLod);
  if (!lodImpostorDraws(gl_FragCoord.xy, length(vEye - uCentre))) discard;
  vec3 o = vEye;
  vec3 dir = normalize(vObject - o);
  // Only rays through the bounding sphere meet the object.
  vec3 oc = o - uCentre;
  float b = dot(oc, dir);
  if (b * b - (dot(oc, oc) - uRadius * uRadius) < 0.0) discard;
  // The three frames around the view direction and their barycentric weights (mapping.rs,
  // frames_around).
  float s = uFrames - 1.0;
  vec2 p = octEncode(normalize(o - uCentre)) * s;
  vec2 cell = clamp(floor(p), vec2(0.0), vec2(s - 1.0));
  vec2 f = p - cell;
  vec2 cells[3];
  vec3 weights;
  if (f.x + f.y <= 1.0) {
    cells[0] = cell; cells[1] = cell + vec2(1.0, 0.0); cells[2] = cell + vec2(0.0, 1.0);
    weights = vec3(1.0 - f.x - f.y, f.x, f.y);
  } else {
    cells[0] = cell + vec2(1.0); cells[1] = cell + vec2(0.0, 1.0); cells[2] = cell + vec2(1.0, 0.0);
    weights = vec3(f.x + f.y - 1.0, 1.0 - f.x, 1.0 - f.y);
  }
  Lookup looks[3];
  // The nearest surface a covered frame finds along the ray.
  float front = 3.0e38;
  for (int k = 0; k < 3; k++) {
    if (weights[k] <= 0.0) continue;
    looks[k] = lookup(cells[k], o, dir, lod);
    if (looks[k].color.a * looks[k].inside >= COVERED) {
      front = min(front, dot(looks[k].position - o, dir));
    }
  }
  vec3 color = vec3(0.0);
  vec3 normal = vec3(0.0);
  vec3 position = vec3(0.0);
  float alpha = 0.0;
  float total = 0.0;
  for (int k = 0; k < 3; k++) {
    float w = weights[k];
    if (w <= 0.0) continue;
    Lookup l = looks[k];
    float coverage = l.color.a * l.inside;
    // Depth-aware blending (render.rs, blend): a frame that sees past the nearest surface
    // fades out. At mip level L a lookup's depth is the mean of 2^L texels, which shrinks the
    // gaps a level-0 blend sees; the tolerance shrinks with it (docs/octahedral.md).
    if (coverage >= COVERED) {
      float behind = (dot(l.position - o, dir) - front) / (DEPTH_AGREEMENT * uRadius * exp2(-lod));
      w *= exp(-behind * behind);
    }
    total += w;
    float a = coverage * w;
    color += l.color.rgb * a;
    normal += l.normal * a;
    position += l.position * a;
    alpha += a;
  }
  // The alpha test; and only what lies ahead of the eye.
  if (total <= 0.0 || alpha < uAlphaTest * total || dot(position / alpha - o, dir) <= 0.0) discard;
  vec3 albedo = color / alpha;
  mat3 toWorld = mat3(vModel);
  vec3 n = length(normal) > 1e-20 ? normalize(toWorld * normal) : normalize(toWorld * -dir);
  // Lambert under a sun and a constant sky, unshadowed (trompe's shading::lambert).
  vec3 irradiance = uAmbient + uSunIrradiance * (max(dot(n, uSunDirection), 0.0) / PI);
  gl_FragColor = vec4(albedo * irradiance, 1.0);
  // Pixel depth offset: the depth of the surface found, not of the card.
  vec4 clip = projectionMatrix * viewMatrix * vModel * vec4(position / alpha, 1.0);
  gl_FragDepth = clamp(clip.z / clip.w * 0.5 + 0.5, 0.0, 1.0);
  #include <tonemapping_fragment>
  #include <colorspace_fragment>
}
`;

/**
 * The impostor's material. `options`: `sunDirection` (world, toward the sun), `sunIrradiance`
 * (a Vector3: the irradiance on a surface facing the sun, W/m², as trompe's scenes give it),
 * `ambient` (a Vector3: the radiance of a constant sky), `parallaxSteps` (4), `alphaTest` (0.5),
 * `mipmaps` (true: levels chosen by each pixel's footprint; false: level 0 only), `crossFade`
 * (false: every pixel; true: the layout's dithered share of them across its fade, the mesh
 * drawing the rest through `crossFadeMaterial`).
 */
export class OctahedralImpostorMaterial extends ShaderMaterial {
  constructor(atlas, options = {}) {
    const l = atlas.layout;
    const coverage = { sphere: 0, hemisphere: 1 }[l.grid.coverage];
    if (coverage === undefined) throw new Error(`grid.coverage ${l.grid.coverage}: not sphere or hemisphere`);
    const distance = l.projection && l.projection.type === 'pinhole' ? l.projection.distance : 0;
    super({
      glslVersion: GLSL3,
      vertexShader,
      fragmentShader,
      side: 2, // DoubleSide: the card is turned toward the eye either way.
      uniforms: {
        uColor: { value: atlas.color },
        uNormalDepth: { value: atlas.normalDepth },
        uCentre: { value: new Vector3(...l.centre) },
        uRadius: { value: l.radius },
        uFrames: { value: l.grid.n },
        uFrameSize: { value: l.frame_size },
        uCoverage: { value: coverage },
        uDistance: { value: distance },
        uParallaxSteps: { value: options.parallaxSteps ?? 4 },
        uAlphaTest: { value: options.alphaTest ?? 0.5 },
        // The coarsest level that still holds two texels a frame.
        uMaxLod: { value: options.mipmaps === false ? 0 : Math.max(0, Math.log2(l.frame_size) - 1) },
        uNear: { value: 0.1 },
        uSunDirection: { value: (options.sunDirection ?? new Vector3(0.3, 1, 0.5)).clone().normalize() },
        uSunIrradiance: { value: options.sunIrradiance ?? new Vector3(3, 3, 3) },
        uAmbient: { value: options.ambient ?? new Vector3(0.3, 0.3, 0.3) },
        uFade: { value: fadeRange(l, options.crossFade) },
      },
    });
    this.atlas = atlas;
  }
}

/** `uFade` for a layout: its cross-fade when asked for and written, else every pixel. */
function fadeRange(layout, crossFade) {
  const f = layout.cross_fade;
  return crossFade && f ? new Vector2(f.start, f.end) : new Vector2(0, 0);
}

/**
 * Makes `material` — one of three's built-in materials, on the mesh an impostor stands for —
 * draw exactly the pixels the impostor leaves across the layout's cross-fade (an impostor made
 * with `crossFade: true`), so that every pixel is drawn once as the object recedes. The distance
 * is the mesh's (or its instance's) matrix applied to the bake's bounding sphere. Returns the
 * material.
 */
export function crossFadeMaterial(material, atlas) {
  const l = atlas.layout;
  const uniforms = { uFade: { value: fadeRange(l, true) }, uFadeCentre: { value: new Vector3(...l.centre) } };
  material.onBeforeCompile = (shader) => {
    Object.assign(shader.uniforms, uniforms);
    shader.vertexShader = shader.vertexShader
      .replace('#include <common>', '#include <common>\nuniform vec3 uFadeCentre;\nflat varying float vFadeDistance;')
      .replace('#include <project_vertex>', `#include <project_vertex>
  {
    mat4 fadeModel = modelMatrix;
#ifdef USE_INSTANCING
    fadeModel = fadeModel * instanceMatrix;
#endif
    vFadeDistance = length(cameraPosition - (fadeModel * vec4(uFadeCentre, 1.0)).xyz) / length(fadeModel[0].xyz);
  }`);
    shader.fragmentShader = shader.fragmentShader
      .replace('#include <common>', `#include <common>\nflat varying float vFadeDistance;\n${CROSS_FADE_GLSL}`)
      .replace('#include <clipping_planes_fragment>',
        '#include <clipping_planes_fragment>\n  if (lodImpostorDraws(gl_FragCoord.xy, vFadeDistance)) discard;');
  };
  material.customProgramCacheKey = () => 'trompe-cross-fade';
  material.needsUpdate = true;
  return material;
}

/**
 * The card's geometry: the layout's cut-out outline (convex, counter-clockwise, units of the
 * radius) as a fan of triangles, or the square of the sphere's diameter where it has none.
 */
export function cardGeometry(outline) {
  const points = outline ?? [[-1, -1], [1, -1], [1, 1], [-1, 1]];
  const geometry = new BufferGeometry();
  geometry.setAttribute('position', new Float32BufferAttribute(points.flatMap(([x, y]) => [x, y, 0]), 3));
  const fan = [];
  for (let k = 1; k + 1 < points.length; k++) fan.push(0, k, k + 1);
  geometry.setIndex(fan);
  return geometry;
}

/**
 * `count` instances of an atlas (an InstancedMesh: set each one's translation, rotation and
 * uniform scale with `setMatrixAt`). Culled by the bounding sphere of the bake.
 */
export class OctahedralImpostor extends InstancedMesh {
  constructor(atlas, count = 1, options = {}) {
    const l = atlas.layout;
    const geometry = cardGeometry(l.card);
    const centre = new Vector3(...l.centre);
    geometry.boundingSphere = new Sphere(centre.clone(), l.radius);
    geometry.boundingBox = new Box3().setFromCenterAndSize(centre, new Vector3().setScalar(2 * l.radius));
    super(geometry, new OctahedralImpostorMaterial(atlas, options), count);
    this.atlas = atlas;
    /** Distance (object units) from which one texel covers one pixel at 1080 rows, 60°. */
    this.switchDistance = l.switch_distance;
  }

  onBeforeRender(renderer, scene, camera) {
    this.material.uniforms.uNear.value = camera.near;
  }
}

/** Loads `url` with `loader` (three's GLTFLoader) as `count` instances. */
export async function loadOctahedralImpostor(url, loader, count = 1, options = {}) {
  return new OctahedralImpostor(await loadOctahedralAtlas(url, loader), count, options);
}
