// Checks that a plain object from the browser has the shape of a message of
// the proto before the gateway hands it to grpc-js: every key a field of
// the message, every value of the field's type (finite numbers, integers in
// range, enum names, nested messages, bounded strings and lists). Walks the
// descriptors @grpc/proto-loader made of proto/vpm/v3/vpm.proto, so it
// follows the proto as it changes.
const kMaxDepth = 8;
const kMaxString = 4096;
const kMaxList = 4096;

const kIntRanges = {
  TYPE_INT32: [-(2 ** 31), 2 ** 31 - 1],
  TYPE_SINT32: [-(2 ** 31), 2 ** 31 - 1],
  TYPE_SFIXED32: [-(2 ** 31), 2 ** 31 - 1],
  TYPE_UINT32: [0, 2 ** 32 - 1],
  TYPE_FIXED32: [0, 2 ** 32 - 1],
  TYPE_INT64: [Number.MIN_SAFE_INTEGER, Number.MAX_SAFE_INTEGER],
  TYPE_SINT64: [Number.MIN_SAFE_INTEGER, Number.MAX_SAFE_INTEGER],
  TYPE_SFIXED64: [Number.MIN_SAFE_INTEGER, Number.MAX_SAFE_INTEGER],
  TYPE_UINT64: [0, Number.MAX_SAFE_INTEGER],
  TYPE_FIXED64: [0, Number.MAX_SAFE_INTEGER],
};

export class ProtoShape {
  // definition: proto-loader's package definition; pkg: the proto package.
  constructor(definition, pkg = 'vpm.v3') {
    this.definition = definition;
    this.pkg = pkg;
  }

  resolve(typeName) {
    const found = this.definition[`${this.pkg}.${typeName}`] ?? this.definition[typeName];
    if (!found) throw new Error(`proto type ${typeName} is unknown`);
    return found;
  }

  // Throws an Error whose message names the path of the first bad value,
  // e.g. "event.camera.azimuth_deg: a finite number".
  check(typeName, value, path = typeName, depth = 0) {
    if (depth > kMaxDepth) throw new Error(`${path}: nested too deep`);
    if (value === null || typeof value !== 'object' || Array.isArray(value)) {
      throw new Error(`${path}: an object`);
    }
    const fields = this.resolve(typeName).type.field;
    for (const [key, v] of Object.entries(value)) {
      const field = fields.find((f) => f.name === key);
      if (!field) throw new Error(`${path}: no field '${key.slice(0, 64)}'`);
      if (v === undefined) continue;
      const at = `${path}.${key}`;
      if (field.label === 'LABEL_REPEATED') {
        if (!Array.isArray(v)) throw new Error(`${at}: a list`);
        if (v.length > kMaxList) throw new Error(`${at}: more than ${kMaxList} entries`);
        v.forEach((x, i) => this.checkValue(field, x, `${at}[${i}]`, depth));
      } else {
        this.checkValue(field, v, at, depth);
      }
    }
  }

  checkValue(field, v, at, depth) {
    const range = kIntRanges[field.type];
    if (range) {
      if (!Number.isInteger(v) || v < range[0] || v > range[1]) {
        throw new Error(`${at}: an integer in [${range[0]}, ${range[1]}]`);
      }
      return;
    }
    switch (field.type) {
      case 'TYPE_DOUBLE':
      case 'TYPE_FLOAT':
        if (typeof v !== 'number' || !Number.isFinite(v)) throw new Error(`${at}: a finite number`);
        return;
      case 'TYPE_BOOL':
        if (typeof v !== 'boolean') throw new Error(`${at}: true or false`);
        return;
      case 'TYPE_STRING':
        if (typeof v !== 'string' || v.length > kMaxString) {
          throw new Error(`${at}: a string of at most ${kMaxString} characters`);
        }
        return;
      case 'TYPE_ENUM': {
        const names = this.resolve(field.typeName).type.value.map((x) => x.name);
        if (!names.includes(v)) throw new Error(`${at}: one of ${names.join(', ')}`);
        return;
      }
      case 'TYPE_MESSAGE':
        this.check(field.typeName, v, at, depth + 1);
        return;
      default:
        throw new Error(`${at}: not accepted from a browser (${field.type})`);
    }
  }
}
