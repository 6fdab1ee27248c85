// The report page's three.js, bundled once at install time (scripts/install-deps.sh runs
// `npm run bundle`) into dist/three-bundle.js, one classic script: Chrome refuses ES-module
// imports across files on a file:// page, so the page cannot import three.js itself.
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
import { RoomEnvironment } from 'three/examples/jsm/environments/RoomEnvironment.js';

window.THREE = Object.assign({}, THREE, { OrbitControls, GLTFLoader, RoomEnvironment });
