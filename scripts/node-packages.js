// Where the npm packages the glTF scripts use are found (validate-gltf.js,
// three-render-glb.js): CELLBAKE_NODE_TOOLS/node_modules (what
// scripts/install-node-tools.sh fills), then the NODE_PATH folders.
'use strict';
const fs = require('fs');
const path = require('path');

// The folder of npm package `name`, or null when no folder holds it.
function package_root(name) {
  const dirs = [];
  if (process.env.CELLBAKE_NODE_TOOLS) dirs.push(path.join(process.env.CELLBAKE_NODE_TOOLS, 'node_modules'));
  dirs.push(...(process.env.NODE_PATH || '').split(path.delimiter).filter(Boolean));
  for (const d of dirs) {
    const p = path.join(d, name);
    if (fs.existsSync(path.join(p, 'package.json'))) return p;
  }
  return null;
}

module.exports = { package_root };
