// Messages a person can act on, from the gRPC errors of the PACS calls
// (ListPacsEndpoints, SearchStudies, ListSeries, LoadVolume of a pacs:
// source, ExportDicom; docs/PACS.md, "Failures"). Unlike explainError, an
// UNAVAILABLE here is the PACS's (vpm-server answered; the caller has
// checked that it is up): the server's text names the endpoint.
import { explainError } from './explain_error.js';
import { GrpcStatus, statusName } from './vpm_client.js';

const kMaxDetailsChars = 500;

// True for the answer of a server started without --pacs.
export function noPacs(err) {
  return err?.code === GrpcStatus.FAILED_PRECONDITION && /no PACS/i.test(err?.details ?? '');
}

// err: a grpc-js error; what: the action, e.g. "Searching orthanc";
// address: vpm-server's HOST:PORT (for the errors explainError words).
export function explainPacsError(err, what, address) {
  const full = String(err?.details || err?.message || err).replace(/\.$/, '');
  const details = full.length > kMaxDetailsChars ? `${full.slice(0, kMaxDetailsChars)}...` : full;
  switch (err?.code) {
    case GrpcStatus.PERMISSION_DENIED:
      return `${what}: not allowed: ${details}. Ask the server's administrator for access ` +
        '(the endpoint\'s "users" in the --pacs file).';
    case GrpcStatus.UNAVAILABLE:
      return `${what}: the PACS is not reachable (${details}). vpm-server is up; try again ` +
        'later, or ask the PACS\'s administrator.';
    case GrpcStatus.DEADLINE_EXCEEDED:
      return `${what}: the PACS did not answer in time (${details}).`;
    case GrpcStatus.INVALID_ARGUMENT:
      return `${what}: ${details}`;
    case GrpcStatus.NOT_FOUND:
      return `${what}: not found: ${details}`;
    case GrpcStatus.RESOURCE_EXHAUSTED:
      return `${what}: too large for the server (${details}). Pick a smaller series, or ask ` +
        'for a larger --pacs-cache-bytes.';
    case GrpcStatus.UNIMPLEMENTED:
      return `${what}: this vpm-server cannot do that (an older version: ${details}).`;
    case GrpcStatus.FAILED_PRECONDITION:
      if (noPacs(err)) return `${what}: this server has no PACS (started without --pacs).`;
      return `${what} failed: FAILED_PRECONDITION: ${details}`;
    case GrpcStatus.CANCELLED:
      return `${what}: cancelled.`;
    default:
      if (err?.code === GrpcStatus.UNAUTHENTICATED) return explainError(err, what, address);
      return `${what} failed: ${statusName(err?.code)}: ${details}`;
  }
}
