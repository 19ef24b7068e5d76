// The 3-D (and 2-D) picture of the running scene with three.js: particles
// as points (and those with a radius as spheres of it, one InstancedMesh),
// links as line segments sharing the points' position buffer, hard
// constraints the same way in a colour of their own (rods as segments, a
// row over one particle as a ring on it), colliders as
// translucent shapes, the simulation box as a wire box, an orbit camera or
// an orthographic one looking along an axis. Scenes are z-up, as in pdyn
// render's `3d` view.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const FREE = new THREE.Color(0.12, 0.30, 0.65);
const FIXED = new THREE.Color(0.80, 0.10, 0.10);
const PICKED = new THREE.Color(0.95, 0.55, 0.05);
const PICK_PIXELS = 12; // how near the cursor a particle must be to be picked
const CONSTRAINT = 0xb0288c; // rods and rings: magenta, apart from springs (grey) and the mouse spring (orange)

/** A ring, white on transparent: the sprite of a particle held by a
 * constraint row over it alone (a pin, a bead on a wire). */
function ringTexture() {
  const canvas = document.createElement('canvas');
  canvas.width = canvas.height = 64;
  const g = canvas.getContext('2d');
  g.strokeStyle = '#fff';
  g.lineWidth = 9;
  g.beginPath();
  g.arc(32, 32, 25, 0, 2 * Math.PI);
  g.stroke();
  return new THREE.CanvasTexture(canvas);
}

// Where a 2-D camera sits relative to its target, and which way is up.
const AXES = {
  xy: { eye: new THREE.Vector3(0, 0, 1), up: new THREE.Vector3(0, 1, 0) },
  xz: { eye: new THREE.Vector3(0, -1, 0), up: new THREE.Vector3(0, 0, 1) },
  yz: { eye: new THREE.Vector3(1, 0, 0), up: new THREE.Vector3(0, 0, 1) },
};

/** Blue - green - yellow - red for s in [0, 1]. */
function ramp(s, out) {
  const stops = [[0.13, 0.25, 0.63], [0.13, 0.63, 0.25], [0.88, 0.75, 0.13], [0.82, 0.13, 0.13]];
  const x = Math.min(Math.max(s, 0), 1) * (stops.length - 1);
  const k = Math.min(Math.floor(x), stops.length - 2), f = x - k;
  out.setRGB(...stops[k].map((a, i) => a + f * (stops[k + 1][i] - a)));
  return out;
}

export class View {
  constructor(container) {
    this.container = container;
    // preserveDrawingBuffer: screenshots and pixel reads see the last frame.
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(window.devicePixelRatio);
    this.renderer.setClearColor(0xf4f4f2);
    container.appendChild(this.renderer.domElement);
    this.scene = new THREE.Scene();
    this.scene.add(new THREE.AmbientLight(0xffffff, 0.8));
    const sun = new THREE.DirectionalLight(0xffffff, 1.2);
    sun.position.set(1, -2, 3);
    this.scene.add(sun);
    this.perspective = new THREE.PerspectiveCamera(45, 1, 0.001, 1000);
    this.perspective.up.set(0, 0, 1);
    this.orthographic = new THREE.OrthographicCamera(-1, 1, 1, -1, -1000, 1000);
    this.camera = this.perspective;
    this.mode = '3d';
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.radius = 1;
    this.count = 0;
    this.fixed = [];
    this.highlight = -1;
    this.showSprings = true;
    this.showConstraints = true;
    this.rods = null;   // constraint rows over two or more particles: LineSegments
    this.rings = null;  // constraint rows over one particle: indexed Points with a ring sprite
    this.constraintSegments = 0;
    this.constraintRings = 0;
    this.bySpeed = false;
    this.speeds = new Float32Array(0);
    this.obstacles = new THREE.Group();
    this.scene.add(this.obstacles);
    this.drag = new THREE.Line(new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(), new THREE.Vector3()]),
                               new THREE.LineBasicMaterial({ color: 0xe08000 }));
    this.drag.visible = false;
    this.scene.add(this.drag);
    this.points = null;
    this.lines = null;
    this.spheres = null; // particles with a radius: an InstancedMesh of unit spheres, scaled
    this.radii = null;
    // Drawn only when something changed (a frame, the camera, a toggle):
    // ten thousand points and sixty thousand lines are not free without a GPU.
    this.dirty = true;
    new ResizeObserver(() => this.resize()).observe(container);
    this.resize();
  }

  resize() {
    const w = Math.max(1, this.container.clientWidth), h = Math.max(1, this.container.clientHeight);
    this.renderer.setSize(w, h);
    this.perspective.aspect = w / h;
    this.perspective.updateProjectionMatrix();
    this.fitOrthographic();
    this.dirty = true;
  }

  fitOrthographic() {
    const w = Math.max(1, this.container.clientWidth), h = Math.max(1, this.container.clientHeight);
    const r = this.radius * 1.15 / (this.orthographic.zoom || 1);
    const a = w / h;
    Object.assign(this.orthographic, a >= 1 ? { left: -r * a, right: r * a, top: r, bottom: -r }
                                            : { left: -r, right: r, top: r / a, bottom: -r / a });
    this.orthographic.zoom = 1;
    this.orthographic.updateProjectionMatrix();
  }

  /** Rebuilds the geometry for a `scene` message; fits the camera if `fit`. */
  setScene(msg, positions, fit) {
    this.count = msg.count;
    this.fixed = msg.fixed;
    for (const o of [this.points, this.lines, this.rods, this.rings]) if (o) { this.scene.remove(o); o.geometry.dispose(); }
    const position = new THREE.BufferAttribute(new Float32Array(3 * msg.count), 3);
    position.setUsage(THREE.DynamicDrawUsage);
    if (positions && positions.length === 3 * msg.count) position.array.set(positions);
    const colour = new THREE.BufferAttribute(new Float32Array(3 * msg.count), 3);
    colour.setUsage(THREE.DynamicDrawUsage);
    const pg = new THREE.BufferGeometry();
    pg.setAttribute('position', position);
    pg.setAttribute('color', colour);
    const size = msg.count > 2000 ? 3 : 7;
    this.points = new THREE.Points(pg, new THREE.PointsMaterial({ size, sizeAttenuation: false, vertexColors: true }));
    this.points.frustumCulled = false;
    const lg = new THREE.BufferGeometry();
    lg.setAttribute('position', position);
    lg.setIndex(msg.links.flat());
    this.lines = new THREE.LineSegments(lg, new THREE.LineBasicMaterial({ color: 0x8a94a6, transparent: true, opacity: 0.6 }));
    this.lines.frustumCulled = false;
    this.lines.visible = this.showSprings;
    this.scene.add(this.lines, this.points);
    this.buildConstraints(msg.constraints ?? [], position);
    if (this.spheres) {
      this.scene.remove(this.spheres);
      this.spheres.geometry.dispose();
      this.spheres.material.dispose();
      this.spheres = null;
    }
    this.radii = msg.radius ?? null;
    if (this.radii && this.radii.length === msg.count && this.radii.some((r) => r > 0)) {
      const fine = msg.count <= 2000; // fewer facets when there are many
      const geometry = new THREE.SphereGeometry(1, fine ? 20 : 8, fine ? 14 : 6);
      this.spheres = new THREE.InstancedMesh(geometry, new THREE.MeshStandardMaterial({ roughness: 0.6 }), msg.count);
      this.spheres.instanceMatrix.setUsage(THREE.DynamicDrawUsage);
      this.spheres.frustumCulled = false;
      this.scene.add(this.spheres);
      this.placeSpheres();
    }
    this.speeds = new Float32Array(msg.count);
    this.msg = msg;
    if (fit) this.fit();
    this.buildObstacles();
    this.recolour();
  }

  /** The constraints' rows over the shared position buffer, so that a frame
   * moves them with no work of their own, however many rows there are: one
   * LineSegments for every row over two particles (a row over more, the
   * chain through them), one indexed Points of ring sprites for the
   * particles a row holds alone (a pin's three rows, a bead's two: one ring). */
  buildConstraints(constraints, position) {
    const segments = [], held = new Set();
    for (const c of constraints) {
      for (const row of c.rows) {
        if (row.length === 1) held.add(row[0]);
        for (let k = 1; k < row.length; ++k) segments.push(row[k - 1], row[k]);
      }
    }
    this.constraintSegments = segments.length / 2;
    this.constraintRings = held.size;
    this.rods = this.rings = null;
    if (segments.length) {
      const g = new THREE.BufferGeometry();
      g.setAttribute('position', position);
      g.setIndex(segments);
      this.rods = new THREE.LineSegments(g, new THREE.LineBasicMaterial({ color: CONSTRAINT }));
      this.rods.frustumCulled = false;
      this.rods.visible = this.showConstraints;
      this.scene.add(this.rods);
    }
    if (held.size) {
      const g = new THREE.BufferGeometry();
      g.setAttribute('position', position);
      g.setIndex([...held]);
      this.ringSprite ??= ringTexture();
      // Drawn over everything: a ring inside a particle's sphere would hide.
      const material = new THREE.PointsMaterial({ color: CONSTRAINT, size: this.count > 2000 ? 9 : 18,
                                                  sizeAttenuation: false, map: this.ringSprite,
                                                  transparent: true, alphaTest: 0.2, depthTest: false });
      this.rings = new THREE.Points(g, material);
      this.rings.frustumCulled = false;
      this.rings.renderOrder = 1;
      this.rings.visible = this.showConstraints;
      this.scene.add(this.rings);
    }
  }

  /** Each sphere at its particle's position, scaled by its radius (0: not drawn). */
  placeSpheres() {
    if (!this.spheres) return;
    const pos = this.points.geometry.attributes.position.array;
    const m = this.spheres.instanceMatrix.array;
    for (let i = 0; i < this.count; ++i) {
      const r = this.radii[i];
      m.set([r, 0, 0, 0, 0, r, 0, 0, 0, 0, r, 0, pos[3 * i], pos[3 * i + 1], pos[3 * i + 2], 1], 16 * i);
    }
    this.spheres.instanceMatrix.needsUpdate = true;
  }

  buildObstacles() {
    this.obstacles.clear();
    const msg = this.msg;
    if (msg.box) this.obstacles.add(this.domainLines(msg.box));
    const material = new THREE.MeshStandardMaterial({ color: 0x9aa59a, transparent: true, opacity: 0.35,
                                                      side: THREE.DoubleSide, depthWrite: false });
    const centre = this.centre || new THREE.Vector3();
    for (const p of msg.planes) {
      const n = new THREE.Vector3(...p.normal).normalize();
      const mesh = new THREE.Mesh(new THREE.PlaneGeometry(4 * this.radius, 4 * this.radius), material);
      mesh.quaternion.setFromUnitVectors(new THREE.Vector3(0, 0, 1), n);
      const point = new THREE.Vector3(...p.point);
      mesh.position.copy(centre).addScaledVector(n, point.clone().sub(centre).dot(n)); // centre projected on the plane
      this.obstacles.add(mesh);
    }
    for (const s of msg.spheres) {
      const mesh = new THREE.Mesh(new THREE.SphereGeometry(s.radius, 32, 16), material);
      mesh.position.set(...s.center);
      this.obstacles.add(mesh);
    }
    for (const b of msg.boxes) {
      const lo = new THREE.Vector3(...b.min), hi = new THREE.Vector3(...b.max);
      const box = new THREE.Box3(lo, hi);
      this.obstacles.add(new THREE.Box3Helper(box, 0x607060));
    }
    for (const m of msg.meshes ?? []) {  // any other collider's surface, as triangles
      const geometry = new THREE.BufferGeometry();
      geometry.setAttribute('position', new THREE.Float32BufferAttribute(m.vertices.flat(), 3));
      geometry.setIndex(m.triangles.flat());
      geometry.computeVertexNormals();
      this.obstacles.add(new THREE.Mesh(geometry, material));
      this.obstacles.add(new THREE.LineSegments(new THREE.WireframeGeometry(geometry),
                                                new THREE.LineBasicMaterial({ color: 0x607060 })));
    }
  }

  /** The simulation box's twelve edges, thin; dashed when some axis is
   * periodic (its faces there are where space repeats, not walls). */
  domainLines(b) {
    const corner = (k) => new THREE.Vector3(k & 1 ? b.max[0] : b.min[0], k & 2 ? b.max[1] : b.min[1],
                                            k & 4 ? b.max[2] : b.min[2]);
    const ends = [];
    for (let k = 0; k < 8; ++k) for (const bit of [1, 2, 4]) if (!(k & bit)) ends.push(corner(k), corner(k | bit));
    const geometry = new THREE.BufferGeometry().setFromPoints(ends);
    const periodic = b.periodic.some((p) => p);
    const size = Math.max(b.max[0] - b.min[0], b.max[1] - b.min[1], b.max[2] - b.min[2]);
    const material = periodic
      ? new THREE.LineDashedMaterial({ color: 0x4d8c73, dashSize: size / 60, gapSize: size / 100 })
      : new THREE.LineBasicMaterial({ color: 0x4d8c73 });
    const lines = new THREE.LineSegments(geometry, material);
    if (periodic) lines.computeLineDistances();
    return lines;
  }

  /** Frames the particles (and the spheres, boxes, meshes and the
   * simulation box) in both cameras. */
  fit() {
    const box = new THREE.Box3();
    const pos = this.points.geometry.attributes.position.array;
    for (let i = 0; i < this.count; ++i) {
      const p = new THREE.Vector3(pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]);
      const r = this.radii ? this.radii[i] : 0;
      box.expandByPoint(p.clone().addScalar(r));
      box.expandByPoint(p.addScalar(-r));
    }
    if (this.msg?.box) { box.expandByPoint(new THREE.Vector3(...this.msg.box.min)); box.expandByPoint(new THREE.Vector3(...this.msg.box.max)); }
    for (const s of this.msg?.spheres ?? []) {
      box.expandByPoint(new THREE.Vector3(...s.center).addScalar(s.radius));
      box.expandByPoint(new THREE.Vector3(...s.center).addScalar(-s.radius));
    }
    for (const b of this.msg?.boxes ?? []) { box.expandByPoint(new THREE.Vector3(...b.min)); box.expandByPoint(new THREE.Vector3(...b.max)); }
    for (const m of this.msg?.meshes ?? []) for (const v of m.vertices) box.expandByPoint(new THREE.Vector3(...v));
    if (box.isEmpty()) box.set(new THREE.Vector3(-0.5, -0.5, -0.5), new THREE.Vector3(0.5, 0.5, 0.5));
    const sphere = box.getBoundingSphere(new THREE.Sphere());
    this.radius = Math.max(sphere.radius, 0.05);
    this.centre = sphere.center.clone();
    this.setMode(this.mode);
  }

  /** '3d' (orbit, perspective) or 'xy', 'xz', 'yz' (orthographic, no rotation). */
  setMode(mode) {
    this.mode = mode;
    const target = this.centre || new THREE.Vector3();
    this.controls.dispose();
    if (mode === '3d') {
      this.camera = this.perspective;
      const d = this.radius / Math.sin(THREE.MathUtils.degToRad(this.perspective.fov / 2)) * 1.1;
      this.camera.position.copy(target).add(new THREE.Vector3(0.6, -1, 0.45).normalize().multiplyScalar(d));
      this.camera.near = d / 1000;
      this.camera.far = d * 100;
      this.camera.updateProjectionMatrix();
    } else {
      this.camera = this.orthographic;
      const { eye, up } = AXES[mode];
      this.camera.up.copy(up);
      this.camera.position.copy(target).addScaledVector(eye, 10 * this.radius);
      this.camera.near = -1000 * this.radius;
      this.camera.far = 1000 * this.radius;
      this.fitOrthographic();
    }
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.target.copy(target);
    this.controls.enableRotate = mode === '3d';
    this.controls.addEventListener('change', () => { this.dirty = true; });
    this.controls.update();
    this.dirty = true;
  }

  /** Copies a frame's positions and speeds into the buffers. */
  setFrame(frame) {
    if (!this.points || frame.count !== this.count) return;
    const position = this.points.geometry.attributes.position;
    position.array.set(frame.positions);
    position.needsUpdate = true;
    this.placeSpheres();
    this.dirty = true;
    this.speeds = frame.speeds;
    if (this.bySpeed) this.recolour();
  }

  recolour() {
    if (!this.points) return;
    const colour = this.points.geometry.attributes.color;
    let top = 0;
    if (this.bySpeed) for (const s of this.speeds) top = Math.max(top, s);
    this.topSpeed = top;
    const c = new THREE.Color();
    for (let i = 0; i < this.count; ++i) {
      if (i === this.highlight) c.copy(PICKED);
      else if (this.fixed[i]) c.copy(FIXED);
      else if (this.bySpeed) ramp(top > 0 ? this.speeds[i] / top : 0, c);
      else c.copy(FREE);
      colour.setXYZ(i, c.r, c.g, c.b);
      if (this.spheres) this.spheres.setColorAt(i, c);
    }
    colour.needsUpdate = true;
    if (this.spheres?.instanceColor) this.spheres.instanceColor.needsUpdate = true;
    this.dirty = true;
  }

  position(id) {
    const a = this.points.geometry.attributes.position.array;
    return new THREE.Vector3(a[3 * id], a[3 * id + 1], a[3 * id + 2]);
  }

  /** Particle `id` on the screen, in page pixels. */
  screenOf(id) {
    const rect = this.renderer.domElement.getBoundingClientRect();
    const p = this.position(id).project(this.camera);
    return { x: rect.left + (p.x + 1) / 2 * rect.width, y: rect.top + (1 - p.y) / 2 * rect.height };
  }

  /** The particle nearest the page point (x, y) within PICK_PIXELS, or -1. */
  pick(x, y) {
    let best = -1, bestD = PICK_PIXELS * PICK_PIXELS;
    for (let i = 0; i < this.count; ++i) {
      const s = this.screenOf(i);
      const d = (s.x - x) ** 2 + (s.y - y) ** 2;
      if (d < bestD) { bestD = d; best = i; }
    }
    return best;
  }

  /** Where the cursor at page point (x, y) is on the plane through `through`
   * facing the camera: the mouse spring's end, a new particle's place. */
  worldAt(x, y, through) {
    const rect = this.renderer.domElement.getBoundingClientRect();
    const ndc = new THREE.Vector2((x - rect.left) / rect.width * 2 - 1, -((y - rect.top) / rect.height) * 2 + 1);
    const ray = new THREE.Raycaster();
    ray.setFromCamera(ndc, this.camera);
    const normal = this.camera.getWorldDirection(new THREE.Vector3());
    const plane = new THREE.Plane().setFromNormalAndCoplanarPoint(normal, through);
    return ray.ray.intersectPlane(plane, new THREE.Vector3()) ?? through.clone();
  }

  target() { return this.controls.target.clone(); }

  showDrag(from, to) {
    if (this.drag.visible !== !!from) this.dirty = true;
    this.drag.visible = !!from;
    if (from && to) {
      this.drag.geometry.setFromPoints([from, to]);
      this.dirty = true;
    }
  }

  showLinks(on) {
    this.showSprings = on;
    if (this.lines) this.lines.visible = on;
    this.dirty = true;
  }

  showConstraintRows(on) {
    this.showConstraints = on;
    for (const o of [this.rods, this.rings]) if (o) o.visible = on;
    this.dirty = true;
  }

  render() {
    this.controls.update();
    if (!this.dirty) return;
    this.dirty = false;
    this.renderer.render(this.scene, this.camera);
  }
}
