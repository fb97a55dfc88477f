// The 3D view: the live model's URDF (urdf-loader on three.js), meshes from the module database
// the gateway serves under /packages/<name>/, joints moved by the joint states.
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import URDFLoader from 'urdf-loader';

export class Viewer {
  constructor(el) {
    this.el = el;
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(window.devicePixelRatio);
    el.appendChild(this.renderer.domElement);
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(0x101317);
    this.camera = new THREE.PerspectiveCamera(45, 1, 0.05, 100);
    this.camera.position.set(3.4, 2.6, 3.4);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.target.set(0, 0.9, 0);
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x334455, 2.0));
    const sun = new THREE.DirectionalLight(0xffffff, 1.5);
    sun.position.set(3, 5, 2);
    this.scene.add(sun);
    this.scene.add(new THREE.GridHelper(6, 12, 0x445566, 0x2a3038));
    this.robot = null;
    this.version = null;
    const loop = () => {
      this.resize();
      this.controls.update();
      this.renderer.render(this.scene, this.camera);
      requestAnimationFrame(loop);
    };
    loop();
  }
  resize() {
    const w = this.el.clientWidth, h = this.el.clientHeight;
    if (w && h && (this.w !== w || this.h !== h)) {
      this.w = w; this.h = h;
      this.renderer.setSize(w, h, false);
      this.camera.aspect = w / h;
      this.camera.updateProjectionMatrix();
    }
  }
  setModel(model) {
    if (this.version === model.version) return;
    this.version = model.version;
    if (this.robot) { this.scene.remove(this.robot); this.robot = null; }
    const loader = new URDFLoader();
    loader.packages = (pkg) => '/packages/' + pkg;
    loader.parseCollision = false;
    try {
      const robot = loader.parse(model.urdf);
      robot.rotation.x = -Math.PI / 2;  // URDF is Z-up, three.js Y-up
      robot.traverse((o) => {
        if (o.isMesh && (!o.material || !o.material.color)) o.material = new THREE.MeshStandardMaterial({ color: 0xb0b8c0 });
      });
      this.scene.add(robot);
      this.robot = robot;
    } catch (e) {
      console.error('URDF', e);
    }
  }
  /// Moves the model's joints; returns how many of the sample's joints the model has.
  setJoints(js) {
    if (!this.robot) return 0;
    let applied = 0;
    for (let i = 0; i < js.name.length; i++) {
      if (this.robot.joints[js.name[i]]) {
        this.robot.setJointValue(js.name[i], js.position[i]);
        applied++;
      }
    }
    this.applied = applied;
    return applied;
  }
}
