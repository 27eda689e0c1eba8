// Messages a person can act on, from gRPC errors of calls to vpm-server.
import { GrpcStatus, statusName } from './vpm_client.js';

const kMaxDetailsChars = 500;

// err: a grpc-js error (code, details); what: the action that failed, e.g.
// "Loading phantom:abdomen" (null: none in particular); address: the
// server's HOST:PORT.
export function explainError(err, what, address) {
  // The server's text may quote what was sent (a file's line, an id): the
  // page gets a bounded part of it.
  const full = String(err?.details || err?.message || err);
  const details = full.length > kMaxDetailsChars ? `${full.slice(0, kMaxDetailsChars)}...` : full;
  const prefix = what ? `${what}: ` : '';
  switch (err?.code) {
    case GrpcStatus.UNAVAILABLE:
      return `${prefix}vpm-server at ${address} is not reachable (${details}). ` +
        'Is it running? The viewer retries on its own.';
    case GrpcStatus.DEADLINE_EXCEEDED:
      return `${prefix}vpm-server at ${address} did not answer in time.`;
    case GrpcStatus.UNAUTHENTICATED:
      return `vpm-server does not know the token you signed in with (${details}). ` +
        'The gateway\'s users must be users of vpm-server too: the same --users file, or a ' +
        'viewer token (VPM_TOKEN) equal to the server\'s --token.';
    case GrpcStatus.FAILED_PRECONDITION:
      // The case calls of a server started without --state-dir.
      if (/keeps no cases/.test(full)) {
        return `${prefix}this server keeps no cases (started without --state-dir).`;
      }
      return `${what} failed: FAILED_PRECONDITION: ${details}`;
    case GrpcStatus.PERMISSION_DENIED:
      return `${prefix}not yours: ${details}`;
    default:
      return `${what} failed: ${statusName(err?.code)}: ${details}`;
  }
}
