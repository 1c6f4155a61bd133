// Independent LAS reader for the tests: reads a LAS file with copc.js (the
// COPC/LAS library from npm, not sapmvs code) and prints its version, point
// count and every `stride`-th point's scaled coordinates as JSON.
//   node las_check.cjs NPM_PREFIX FILE.las STRIDE
const path = require('path');
const fs = require('fs');
const {Las} = require(path.join(process.argv[2], 'node_modules', 'copc'));
const buf = new Uint8Array(fs.readFileSync(process.argv[3]));
const stride = Math.max(1, parseInt(process.argv[4] || '1', 10));
const header = Las.Header.parse(buf);
const begin = header.pointDataOffset;
const end = begin + header.pointCount * header.pointDataRecordLength;
const view = Las.View.create(buf.subarray(begin, end), header);
const gx = view.getter('X'), gy = view.getter('Y'), gz = view.getter('Z');
const points = [];
for (let i = 0; i < view.pointCount; i += stride) points.push([i, gx(i), gy(i), gz(i)]);
process.stdout.write(JSON.stringify({
  version: `${header.majorVersion}.${header.minorVersion}`,
  format: header.pointDataRecordFormat,
  count: header.pointCount,
  points,
}) + '\n');
