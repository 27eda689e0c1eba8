// The meshes the tabs of this gateway use, so that a tab going away deletes
// a mesh only when no other tab here shows it or is about to (a BuildMesh in
// flight on its volume may return that very mesh: the server gives equal
// parameters the mesh it holds). Tabs of other gateways are covered by the
// server itself: it refuses to delete a mesh a session uses.
export class MeshRefs {
  constructor() {
    this.holds = new Map();     // mesh id -> tabs' holds
    this.building = new Map();  // volume id -> BuildMesh calls in flight
    this.deleting = new Map();  // volume id -> Set of DeleteMesh calls in flight
  }

  // A DeleteMesh of a mesh on `volumeId` in flight: a BuildMesh on that
  // volume waits for it (else the server could answer the build with the
  // mesh the delete then removes).
  deleteStarted(volumeId, promise) {
    if (!this.deleting.has(volumeId)) this.deleting.set(volumeId, new Set());
    const set = this.deleting.get(volumeId);
    set.add(promise);
    promise.finally(() => {
      set.delete(promise);
      if (set.size === 0 && this.deleting.get(volumeId) === set) this.deleting.delete(volumeId);
    }).catch(() => {});
  }

  // Resolves once no DeleteMesh on `volumeId` is in flight.
  async quiet(volumeId) {
    while (this.deleting.has(volumeId)) await Promise.allSettled([...this.deleting.get(volumeId)]);
  }

  // Around a BuildMesh on `volumeId` (after quiet()); returns the function
  // that ends it.
  build(volumeId) {
    this.building.set(volumeId, (this.building.get(volumeId) ?? 0) + 1);
    let done = false;
    return () => {
      if (done) return;
      done = true;
      const left = this.building.get(volumeId) - 1;
      if (left > 0) this.building.set(volumeId, left);
      else this.building.delete(volumeId);
    };
  }

  hold(meshId) {
    this.holds.set(meshId, (this.holds.get(meshId) ?? 0) + 1);
  }

  release(meshId) {
    const left = (this.holds.get(meshId) ?? 1) - 1;
    if (left > 0) this.holds.set(meshId, left);
    else this.holds.delete(meshId);
  }

  inUse(meshId, volumeId) {
    return this.holds.has(meshId) || this.building.has(volumeId);
  }
}
