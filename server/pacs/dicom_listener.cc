#include "server/pacs/dicom_listener.h"

#include <dcmtk/config/osconfig.h>  // first among DCMTK headers
#include <dcmtk/dcmnet/assoc.h>
#include <dcmtk/dcmnet/dcmtrans.h>
#include <dcmtk/dcmnet/diutil.h>
#include <dcmtk/dcmnet/dul.h>
#include <dcmtk/dcmnet/scpcfg.h>

#include <sys/socket.h>

namespace vpm::pacs {
namespace {

// What the listener accepts: every storage class DCMTK knows, uncompressed
// first, then the compressed syntaxes the readers decode; and C-ECHO.
DcmSCPConfig ListenerConfig(const DicomListener::Options& o) {
  DcmSCPConfig config;
  config.setAETitle(o.address.ae_title.c_str());
  config.setACSETimeout(static_cast<Uint32>(o.acse_timeout_s));
  config.setDIMSETimeout(static_cast<Uint32>(o.dimse_timeout_s));
  config.setDIMSEBlockingMode(DIMSE_NONBLOCKING);
  config.setProgressNotificationMode(OFTrue);
  config.setHostLookupEnabled(OFFalse);
  OFList<OFString> plain, images;
  for (const char* uid : {UID_LittleEndianExplicitTransferSyntax,
                          UID_LittleEndianImplicitTransferSyntax}) {
    plain.push_back(uid);
    images.push_back(uid);
  }
  for (const char* uid :
       {UID_BigEndianExplicitTransferSyntax, UID_JPEG2000LosslessOnlyTransferSyntax,
        UID_JPEG2000TransferSyntax, UID_JPEGProcess14SV1TransferSyntax,
        UID_JPEGProcess14TransferSyntax, UID_JPEGProcess1TransferSyntax,
        UID_JPEGProcess2_4TransferSyntax, UID_JPEGLSLosslessTransferSyntax,
        UID_JPEGLSLossyTransferSyntax, UID_RLELosslessTransferSyntax}) {
    images.push_back(uid);
  }
  config.addPresentationContext(UID_VerificationSOPClass, plain);
  for (int n = 0; n < numberOfDcmAllStorageSOPClassUIDs; ++n) {
    config.addPresentationContext(dcmAllStorageSOPClassUIDs[n], images);
  }
  return config;
}

// The socket of an association, so that Stop() can cut it: DCMTK keeps
// getSocket() protected; a member pointer taken in a derived class reaches it.
struct SocketOfConnection : DcmTransportConnection {
  static int Of(DcmTransportConnection* connection) {
    DcmNativeSocketType (DcmTransportConnection::*get)() = &SocketOfConnection::getSocket;
    return static_cast<int>((connection->*get)());
  }
};

bool IsLoopbackHost(const std::string& host) {
  return host == "localhost" || host.starts_with("127.");
}

}  // namespace

struct DicomListener::Config {
  DcmSharedSCPConfig shared;
};

DicomListener::DicomListener(Options options) : options_(std::move(options)) {}

Result<std::unique_ptr<DicomListener>> DicomListener::Start(Options options) {
  if (options.store == nullptr) return absl::InvalidArgumentError("--dicom-listen: no store");
  std::unique_ptr<DicomListener> listener(new DicomListener(std::move(options)));
  const Options& o = listener->options_;
  listener->config_ = std::make_unique<Config>(Config{DcmSharedSCPConfig(ListenerConfig(o))});
  T_ASC_Network* network = nullptr;
  const OFCondition opened = ASC_initializeNetwork(NET_ACCEPTOR, o.address.port,
                                                   static_cast<int>(o.acse_timeout_s), &network);
  if (opened.bad()) {
    return absl::InvalidArgumentError(StrCat("--dicom-listen ", o.address.ae_title, "@",
                                             o.address.host, ":", o.address.port,
                                             ": cannot listen there: ", opened.text()));
  }
  listener->network_ = network;
  listener->port_ = network->acceptorPort;
  listener->acceptor_ = std::thread([l = listener.get()] { l->AcceptLoop(); });
  return listener;
}

DicomListener::~DicomListener() { Stop(); }

void DicomListener::Stop() {
  if (stopping_.exchange(true)) {
    if (acceptor_.joinable()) acceptor_.join();
    return;
  }
  // Wakes the acceptor's wait for a connection at once.
  if (network_ != nullptr) ::shutdown(DUL_networkSocket(network_->network), SHUT_RDWR);
  if (acceptor_.joinable()) acceptor_.join();
  std::list<Worker> workers;
  {
    std::lock_guard lock(mutex_);
    for (Worker& w : workers_) {
      if (!w.done && w.socket >= 0) ::shutdown(w.socket, SHUT_RDWR);
    }
    workers.splice(workers.end(), workers_);
  }
  for (Worker& w : workers) {
    if (w.thread.joinable()) w.thread.join();
  }
  if (network_ != nullptr) ASC_dropNetwork(&network_);
  network_ = nullptr;
}

void DicomListener::ReapFinished() {
  std::list<Worker> finished;
  {
    std::lock_guard lock(mutex_);
    for (auto it = workers_.begin(); it != workers_.end();) {
      auto next = std::next(it);
      if (it->done) finished.splice(finished.end(), workers_, it);
      it = next;
    }
  }
  for (Worker& w : finished) w.thread.join();
}

void DicomListener::AcceptLoop() {
  while (!stopping_) {
    T_ASC_Association* association = nullptr;
    const OFCondition got = ASC_receiveAssociation(network_, &association, ASC_DEFAULTMAXPDU,
                                                   nullptr, nullptr, OFFalse, DUL_NOBLOCK, 1);
    ReapFinished();
    if (got.bad() || stopping_) {
      if (association != nullptr) {
        ASC_dropSCPAssociation(association);
        ASC_destroyAssociation(&association);
      }
      continue;
    }
    RunAssociation(association);
  }
}

void DicomListener::RunAssociation(T_ASC_Association* association) {
  std::lock_guard lock(mutex_);
  if (static_cast<int>(workers_.size()) >= options_.max_associations) {
    T_ASC_RejectParameters reject = {ASC_RESULT_REJECTEDTRANSIENT,
                                     ASC_SOURCE_SERVICEPROVIDER_PRESENTATION_RELATED,
                                     ASC_REASON_SP_PRES_LOCALLIMITEXCEEDED};
    ASC_rejectAssociation(association, &reject);
    ASC_dropSCPAssociation(association);
    ASC_destroyAssociation(&association);
    return;
  }
  DcmTransportConnection* connection = DUL_getTransportConnection(association->DULassociation);
  Worker& worker = workers_.emplace_back();
  worker.socket = connection != nullptr ? SocketOfConnection::Of(connection) : -1;
  StoreAssociation::Context context{.ae_title = options_.address.ae_title,
                                    .loopback_only = IsLoopbackHost(options_.address.host),
                                    .max_instance_bytes = options_.max_instance_bytes,
                                    .store = options_.store,
                                    .moves = options_.moves,
                                    .own_move_originators = options_.own_move_originators,
                                    .report = options_.on_series};
  Worker* w = &worker;
  // Before the association's socket closes, Stop() must no longer cut it.
  context.on_end = [this, w] {
    std::lock_guard end_lock(mutex_);
    w->socket = -1;
  };
  worker.thread = std::thread([this, association, context, w]() mutable {
    {
      StoreAssociation scp(std::move(context), w->socket);
      scp.setSharedConfig(config_->shared);
      scp.run(association);  // takes the association: dropped and freed at its end
    }
    std::lock_guard done_lock(mutex_);
    w->done = true;
    w->socket = -1;
  });
}

}  // namespace vpm::pacs
