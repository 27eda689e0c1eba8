// The Volume picker (#volume): the built-in phantoms, the volumes loaded on
// the server (ListVolumes), and which entry is the volume open, so that the
// picker names what is shown and Open reopens it, unless the user has
// picked another entry since.
export class VolumePicker {
  // select: the <select>; loaded: its <optgroup> of the server's volumes.
  constructor({ select, loaded }) {
    Object.assign(this, { select, loaded, open: null, userPicked: false });
    select.addEventListener('change', () => { this.userPicked = true; });
  }

  // volumes: ListVolumes' VolumeInfo list.
  fill(volumes) {
    const before = this.select.value;
    this.loaded.replaceChildren(...volumes.map((v) => {
      const option = document.createElement('option');
      option.value = `volume:${v.volume_id}`;
      option.textContent = `${v.volume_id}: ${v.source} (${v.dims.join(' x ')})`;
      return option;
    }));
    if (this.userPicked && this.has(before)) this.select.value = before;
    else this.showOpen();
  }

  // volume: the VolumeInfo just opened.
  opened(volume) {
    Object.assign(this, { open: volume, userPicked: false });
    this.showOpen();
  }

  // {volume_id} or {source}: what Open opens.
  intent() {
    const [kind, ...rest] = this.select.value.split(':');
    const value = rest.join(':');
    return kind === 'volume' ? { volume_id: value } : { source: value };
  }

  has(value) {
    return [...this.select.options].some((o) => o.value === value);
  }

  showOpen() {
    const v = this.open;
    if (!v) return;
    const value = [`volume:${v.volume_id}`, `source:${v.source}`].find((x) => this.has(x));
    if (value) this.select.value = value;
  }
}
