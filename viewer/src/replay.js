// The 3D replay: the world's obstacles, the vehicle with its rotors coloured by health and its
// real attitude (the yaw spin included), the reference and flown paths, the plans as they changed
// and the LiDAR map as it was built. World frame z up, as the simulator's.
import * as THREE from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";
import { indexAt } from "./series.js";

const HEALTH_COLORS = {
  ok: 0x2ca02c, // no fault injected
  fault: 0xd62728, // the simulator injected a fault (truth)
};
// The FDD's diagnosis (health_i): 0 ok, 1 motor failed, 2 propeller failed, 3 degraded, 4 failed.
const DIAGNOSIS_COLORS = [0xffffff, 0xff7f0e, 0xff7f0e, 0xffd700, 0xff7f0e];

function line(points, color, opacity = 1, width = 1) {
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute("position", new THREE.Float32BufferAttribute(points, 3));
  const material = new THREE.LineBasicMaterial({ color, transparent: opacity < 1, opacity, linewidth: width });
  return new THREE.Line(geometry, material);
}

function columnsToPoints(series, x, y, z) {
  const out = new Float32Array(series[x].length * 3);
  for (let i = 0; i < series[x].length; i += 1) {
    out[3 * i] = series[x][i];
    out[3 * i + 1] = series[y][i];
    out[3 * i + 2] = series[z][i];
  }
  return out;
}

export class Replay {
  constructor(container, data) {
    this.data = data;
    this.series = data.series;
    this.scene = data.scene;
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(Math.min(2, window.devicePixelRatio || 1));
    container.appendChild(this.renderer.domElement);
    this.container = container;
    this.world = new THREE.Scene();
    this.world.background = new THREE.Color(0xdfe6ee);
    this.camera = new THREE.PerspectiveCamera(50, 1, 0.05, 500);
    this.camera.up.set(0, 0, 1);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.enableDamping = false;
    this.controls.addEventListener("change", () => this.render());
    this.follow = true;

    this.world.add(new THREE.AmbientLight(0xffffff, 0.75));
    const sun = new THREE.DirectionalLight(0xffffff, 1.6);
    sun.position.set(10, -14, 20);
    this.world.add(sun);

    this.bounds = new THREE.Box3();
    this.addPaths();
    this.addObstacles();
    this.addGround();
    this.addVehicle();
    this.addPlans();
    this.addMap();

    const center = this.bounds.getCenter(new THREE.Vector3());
    const size = this.bounds.getSize(new THREE.Vector3()).length();
    // Start behind and above the vehicle's first position, at a distance that shows its
    // surroundings; "follow" keeps this offset as the vehicle moves.
    this.viewDistance = Math.max(1.2, Math.min(5, 0.1 * size));
    const s0 = this.series;
    const start = new THREE.Vector3(s0.p_x[0], s0.p_y[0], s0.p_z[0]);
    this.camera.position.set(start.x - this.viewDistance, start.y - 0.8 * this.viewDistance, start.z + 0.7 * this.viewDistance);
    this.controls.target.copy(this.follow ? start : center);
    this.resize();
    window.addEventListener("resize", () => this.resize());
  }

  addGround() {
    const b = this.bounds;
    const extent = Math.max(10, Math.ceil(Math.max(b.max.x - b.min.x, b.max.y - b.min.y) + 6));
    const grid = new THREE.GridHelper(extent, extent, 0x8a94a6, 0xb8c0cc);
    grid.rotation.x = Math.PI / 2; // the helper lies in x-z; the world's ground is x-y
    const c = b.getCenter(new THREE.Vector3());
    grid.position.set(Math.round(c.x), Math.round(c.y), 0);
    this.world.add(grid);
  }

  addPaths() {
    const s = this.series;
    const flown = columnsToPoints(s, "p_x", "p_y", "p_z");
    const reference = columnsToPoints(s, "ref_p_x", "ref_p_y", "ref_p_z");
    this.referenceLine = line(reference, 0x1f77b4, 0.9);
    this.flownLine = line(flown, 0xd62728, 1);
    this.world.add(this.referenceLine, this.flownLine);
    this.flownLine.geometry.computeBoundingBox();
    this.bounds.union(this.flownLine.geometry.boundingBox);
    this.referenceLine.geometry.computeBoundingBox();
    this.bounds.union(this.referenceLine.geometry.boundingBox);
  }

  addObstacles() {
    const world = this.scene.world;
    // Boxes (walls, furniture) are see-through with solid edges, so that they never hide the vehicle.
    const boxMaterial = new THREE.MeshLambertMaterial({ color: 0xa08770, transparent: true, opacity: 0.28, depthWrite: false });
    const edgeMaterial = new THREE.LineBasicMaterial({ color: 0x6d5a48 });
    for (const b of world.boxes) {
      const geometry = new THREE.BoxGeometry(...b.size_m);
      const mesh = new THREE.Mesh(geometry, boxMaterial);
      mesh.add(new THREE.LineSegments(new THREE.EdgesGeometry(geometry), edgeMaterial));
      mesh.position.set(...b.center_m);
      mesh.rotation.z = b.yaw_rad;
      this.world.add(mesh);
    }
    if (world.cylinders.length > 0) {
      // Trees: one instanced unit cylinder (axis along z after the rotation below).
      const geometry = new THREE.CylinderGeometry(1, 1, 1, 16);
      geometry.rotateX(Math.PI / 2);
      const trees = new THREE.InstancedMesh(geometry, new THREE.MeshLambertMaterial({ color: 0x6b8e4e }), world.cylinders.length);
      const m = new THREE.Matrix4();
      world.cylinders.forEach((c, i) => {
        m.makeScale(c.radius_m, c.radius_m, c.height_m);
        m.setPosition(c.center_m[0], c.center_m[1], 0.5 * c.height_m);
        trees.setMatrixAt(i, m);
      });
      this.world.add(trees);
    }
    const movingMaterial = new THREE.MeshLambertMaterial({ color: 0xd0602a, transparent: true, opacity: 0.6 });
    this.movingBoxes = world.moving_boxes.map((mb) => {
      const mesh = new THREE.Mesh(new THREE.BoxGeometry(...mb.size_m), movingMaterial);
      this.world.add(mesh);
      return { mesh, t: mb.t_s, c: mb.center_m };
    });
  }

  addVehicle() {
    const rotors = this.scene.vehicle.rotors;
    this.vehicle = new THREE.Group();
    // An assembly (scene.vehicle.units) is drawn as its docked units, each a body with arms to its
    // own rotors; a single vehicle is one unit at the centre of gravity.
    const units = this.scene.vehicle.units || [{ center_m: [0, 0, 0] }];
    const unitOf = (r) => (r.unit === undefined ? 0 : r.unit);
    let arm = 0.1;
    for (const r of rotors) {
      const c = units[unitOf(r)].center_m;
      arm = Math.max(arm, Math.hypot(r.position_m[0] - c[0], r.position_m[1] - c[1]));
    }
    // Drawn larger than life when the scene is large, so that it stays visible.
    const bodyMaterial = new THREE.MeshLambertMaterial({ color: 0x30343c });
    let front = 0;
    for (const u of units) {
      const body = new THREE.Mesh(new THREE.BoxGeometry(0.5 * arm, 0.5 * arm, 0.15 * arm), bodyMaterial);
      body.position.set(...u.center_m);
      this.vehicle.add(body);
      front = Math.max(front, u.center_m[0]);
    }
    const nose = new THREE.Mesh(new THREE.ConeGeometry(0.08 * arm, 0.3 * arm, 12), new THREE.MeshLambertMaterial({ color: 0xffffff }));
    nose.rotation.z = -Math.PI / 2;
    nose.position.set(front + 0.4 * arm, 0, 0);
    this.vehicle.add(nose);
    this.rotorDiscs = [];
    this.rotorRings = [];
    for (const r of rotors) {
      const p = new THREE.Vector3(...r.position_m);
      const c = units[unitOf(r)].center_m;
      const armLine = line([c[0], c[1], c[2], p.x, p.y, p.z], 0x30343c);
      this.vehicle.add(armLine);
      const disc = new THREE.Mesh(new THREE.CylinderGeometry(0.42 * arm, 0.42 * arm, 0.03 * arm, 24),
                                  new THREE.MeshLambertMaterial({ color: HEALTH_COLORS.ok, transparent: true, opacity: 0.85 }));
      disc.rotation.x = Math.PI / 2;
      disc.position.copy(p);
      this.vehicle.add(disc);
      this.rotorDiscs.push(disc);
      const ring = new THREE.Mesh(new THREE.TorusGeometry(0.48 * arm, 0.04 * arm, 8, 32), new THREE.MeshBasicMaterial({ color: DIAGNOSIS_COLORS[0] }));
      ring.position.copy(p);
      this.vehicle.add(ring);
      this.rotorRings.push(ring);
    }
    const sceneSize = this.bounds.getSize(new THREE.Vector3()).length();
    this.vehicleScale = Math.max(1, sceneSize / 40);
    this.vehicle.scale.setScalar(this.vehicleScale);
    this.world.add(this.vehicle);
  }

  addPlans() {
    this.plans = (this.scene.plans || []).map((p) => {
      const obj = line(p.points_m.flat(), 0x00a0e0, 1);
      obj.visible = false;
      this.world.add(obj);
      return { t: p.t_s, obj };
    });
  }

  addMap() {
    const map = this.scene.map;
    this.mapSnapshots = map ? map.snapshots : [];
    this.mapIndex = -1;
    this.voxels = new Map();
    if (!map) return;
    let capacity = 0;
    let count = 0;
    for (const s of this.mapSnapshots) {
      count += s.added.length / 3 - s.removed.length / 3;
      capacity = Math.max(capacity, count);
    }
    const res = map.resolution_m;
    this.mapResolution = res;
    // Half-size cubes: the map reads as a lattice the vehicle and its paths stay visible through.
    const geometry = new THREE.BoxGeometry(0.5 * res, 0.5 * res, 0.5 * res);
    this.mapMesh = new THREE.InstancedMesh(geometry, new THREE.MeshLambertMaterial({ color: 0x4060c0 }), Math.max(1, capacity));
    this.mapMesh.count = 0;
    this.mapMesh.instanceMatrix.setUsage(THREE.DynamicDrawUsage);
    this.mapMesh.setColorAt(0, new THREE.Color(0x4060c0)); // the colour buffer exists from the first frame
    this.mapMesh.frustumCulled = false; // its bounds change with every snapshot
    this.world.add(this.mapMesh);
  }

  /** The map as it was at the snapshot `index` (replays changes; restarts when going back). */
  showMap(index) {
    if (!this.mapMesh || index === this.mapIndex) return;
    if (index < this.mapIndex) {
      this.voxels.clear();
      this.mapIndex = -1;
    }
    for (let k = this.mapIndex + 1; k <= index; k += 1) {
      const s = this.mapSnapshots[k];
      for (let i = 0; i < s.removed.length; i += 3) this.voxels.delete(`${s.removed[i]},${s.removed[i + 1]},${s.removed[i + 2]}`);
      for (let i = 0; i < s.added.length; i += 3) this.voxels.set(`${s.added[i]},${s.added[i + 1]},${s.added[i + 2]}`, [s.added[i], s.added[i + 1], s.added[i + 2]]);
    }
    this.mapIndex = index;
    const m = new THREE.Matrix4();
    const c = new THREE.Color();
    const res = this.mapResolution;
    let n = 0;
    for (const v of this.voxels.values()) {
      if (v[2] < 1) continue; // ground returns (below one voxel): the floor is drawn already
      m.makeTranslation((v[0] + 0.5) * res, (v[1] + 0.5) * res, (v[2] + 0.5) * res);
      this.mapMesh.setMatrixAt(n, m);
      c.setHSL(0.62 - 0.1 * Math.min(1, Math.max(0, (v[2] * res) / 4)), 0.55, 0.5);
      this.mapMesh.setColorAt(n, c);
      n += 1;
    }
    this.mapMesh.count = n;
    this.mapMesh.instanceMatrix.needsUpdate = true;
    if (this.mapMesh.instanceColor) this.mapMesh.instanceColor.needsUpdate = true;
  }

  /** Shows or hides the LiDAR map. */
  setMapVisible(visible) {
    if (this.mapMesh) this.mapMesh.visible = visible;
    this.render();
  }

  /** Places everything at time t [s]. */
  setTime(t) {
    const s = this.series;
    const i = indexAt(s.t, t);
    const j = Math.min(i + 1, s.t.length - 1);
    const a = j > i ? Math.min(1, Math.max(0, (t - s.t[i]) / (s.t[j] - s.t[i]))) : 0;
    const lerp = (name) => s[name][i] + a * (s[name][j] - s[name][i]);
    this.vehicle.position.set(lerp("p_x"), lerp("p_y"), lerp("p_z"));
    const qi = new THREE.Quaternion(s.q_x[i], s.q_y[i], s.q_z[i], s.q_w[i]);
    const qj = new THREE.Quaternion(s.q_x[j], s.q_y[j], s.q_z[j], s.q_w[j]);
    this.vehicle.quaternion.copy(qi.slerp(qj, a));
    this.rotorDiscs.forEach((disc, r) => {
      const fault = s[`fault_${r}`] ? s[`fault_${r}`][i] : 0;  // no fault_i columns without a truth
      disc.material.color.setHex(fault > 0 ? HEALTH_COLORS.fault : HEALTH_COLORS.ok);
    });
    this.rotorRings.forEach((ring, r) => {
      const h = s[`health_${r}`] ? s[`health_${r}`][i] : 0;
      ring.material.color.setHex(DIAGNOSIS_COLORS[h] ?? DIAGNOSIS_COLORS[0]);
    });
    this.flownLine.geometry.setDrawRange(0, i + 1);
    for (const mb of this.movingBoxes) {
      if (mb.t.length === 0) continue;
      const k = indexAt(mb.t, t);
      mb.mesh.position.set(...mb.c[k]);
    }
    // The plan being followed at t, and the one before it, fainter.
    let current = -1;
    for (let k = 0; k < this.plans.length && this.plans[k].t <= t; k += 1) current = k;
    this.plans.forEach((p, k) => {
      p.obj.visible = k === current || k === current - 1;
      p.obj.material.opacity = k === current ? 1 : 0.35;
      p.obj.material.transparent = k !== current;
    });
    let snapshot = -1;
    for (let k = 0; k < this.mapSnapshots.length && this.mapSnapshots[k].t_s <= t; k += 1) snapshot = k;
    this.showMap(snapshot);
    if (this.follow) {
      const offset = this.camera.position.clone().sub(this.controls.target);
      this.controls.target.copy(this.vehicle.position);
      this.camera.position.copy(this.vehicle.position).add(offset);
      this.controls.update();
    }
    this.render();
  }

  resize() {
    const w = Math.max(1, this.container.clientWidth);
    const h = Math.max(1, this.container.clientHeight);
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.render();
  }

  render() {
    this.renderer.render(this.world, this.camera);
  }
}
