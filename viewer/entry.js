// Everything the swarf HTML viewer uses from three.js, as one namespace (global `THREE` once
// bundled by build.sh): the whole core API plus OrbitControls from the examples.
export * from 'three';
export { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
