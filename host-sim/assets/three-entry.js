// The parts of three.js that viewer.html uses, bundled by build-three.sh into
// three.min.js (an IIFE defining the global THREE), which render/viewer.rs
// inlines into every viewer.html.
export {
  AmbientLight, ArrowHelper, BufferGeometry, Color, CylinderGeometry,
  DirectionalLight, DoubleSide, Float32BufferAttribute, GridHelper, Group,
  HemisphereLight, Line, LineBasicMaterial, Matrix4, Mesh, MeshLambertMaterial,
  PerspectiveCamera, Quaternion, Scene, SphereGeometry, Vector3, WebGLRenderer,
} from 'three';
export { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
