// Independent LAS readers for the tests, both from npm and neither sapmvs
// code: copc.js (the COPC/LAS library) and @loaders.gl/las (the loader behind
// deck.gl and kepler.gl). Prints, as JSON, what each makes of FILE: version,
// point count, every `stride`-th point's scaled coordinates, and (copc.js,
// which reads Extra Bytes; @loaders.gl/las skips them by the record length)
// the Extra Bytes fields and their values at those points.
//   node las_check.cjs NPM_PREFIX FILE.las STRIDE
// A reader that is not installed or that refuses the file gives
// {"error": "..."} in its place.
const path = require('path');
const fs = require('fs');
const modules = path.join(process.argv[2], 'node_modules');
const file = process.argv[3];
const stride = Math.max(1, parseInt(process.argv[4] || '1', 10));
const bytes = new Uint8Array(fs.readFileSync(file));

async function withCopc() {
  const {Las} = require(path.join(modules, 'copc'));
  const header = Las.Header.parse(bytes);
  const vlrs = await Las.Vlr.walk(file, header);
  const ebVlr = Las.Vlr.find(vlrs, 'LASF_Spec', 4);
  const eb = ebVlr ? Las.ExtraBytes.parse(await Las.Vlr.fetch(file, ebVlr)) : [];
  const begin = header.pointDataOffset;
  const end = begin + header.pointCount * header.pointDataRecordLength;
  const view = Las.View.create(bytes.subarray(begin, end), header, eb);
  const names = ['X', 'Y', 'Z', ...eb.map((e) => e.name)];
  const getters = names.map((n) => view.getter(n));
  const points = [];
  for (let i = 0; i < view.pointCount; i += stride) points.push([i, ...getters.map((g) => g(i))]);
  return {
    version: `${header.majorVersion}.${header.minorVersion}`,
    format: header.pointDataRecordFormat,
    count: header.pointCount,
    extra_bytes: eb.map((e) => ({name: e.name, type: e.type, length: e.length, min: e.min, max: e.max})),
    fields: names,
    points,
  };
}

async function withLoadersGl() {
  const {parse} = require(path.join(modules, '@loaders.gl', 'core'));
  const {LASLoader} = require(path.join(modules, '@loaders.gl', 'las'));
  const buffer = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);
  // fp64: float32 positions lose decimetres at UTM northings.
  const mesh = await parse(buffer, LASLoader, {las: {fp64: true}, worker: false});
  const xyz = mesh.attributes.POSITION.value;
  const points = [];
  for (let i = 0; i < mesh.header.vertexCount; i += stride) {
    points.push([i, xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]]);
  }
  return {
    count: mesh.header.vertexCount,
    format: mesh.loaderData.pointsFormatId,
    attributes: Object.keys(mesh.attributes),
    points,
  };
}

async function attempt(f) {
  try {
    return await f();
  } catch (e) {
    return {error: String(e && e.message ? e.message : e)};
  }
}

(async () => {
  const result = {copc: await attempt(withCopc), loaders_gl: await attempt(withLoadersGl)};
  process.stdout.write(JSON.stringify(result) + '\n');
})();
