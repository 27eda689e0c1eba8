// SqlConnection over libpq (PostgreSQL), and the PostgreSQL case store:
// replicas behind a balancer share their cases through it.
#include <libpq-fe.h>

#include <cstdio>
#include <cstring>
#include <memory>

#include "server/cases/open_case_store.h"
#include "server/cases/postgres_connection.h"
#include "server/cases/sql_case_store.h"

namespace vpm::cases {
namespace {

constexpr Oid kByteaOid = 17;
constexpr Oid kInt8Oid = 20;
constexpr Oid kInt4Oid = 23;
constexpr Oid kFloat8Oid = 701;

struct ResultDeleter {
  void operator()(PGresult* r) const { PQclear(r); }
};
using PgResult = std::unique_ptr<PGresult, ResultDeleter>;
struct ConnDeleter {
  void operator()(PGconn* c) const { PQfinish(c); }
};
using PgConn = std::unique_ptr<PGconn, ConnDeleter>;

// The project's error for a failed statement, from its SQLSTATE.
Status PostgresError(const PGresult* result, PGconn* conn, std::string_view what) {
  const char* state = result != nullptr ? PQresultErrorField(result, PG_DIAG_SQLSTATE) : nullptr;
  std::string detail = result != nullptr ? PQresultErrorMessage(result) : PQerrorMessage(conn);
  while (!detail.empty() && (detail.back() == '\n' || detail.back() == ' ')) detail.pop_back();
  const std::string context = StrCat("case store: could not ", what, " (PostgreSQL: ", detail, ")");
  const std::string code = state != nullptr ? state : "";
  if (PQstatus(conn) != CONNECTION_OK || code.starts_with("08") || code.starts_with("57P")) {
    return absl::UnavailableError(
        StrCat(context, ": the database server cannot be reached; retry"));
  }
  if (code == "53100") {
    return absl::ResourceExhaustedError(
        StrCat(context, ": the database server's disk is full; free space, then retry"));
  }
  if (code.starts_with("53")) return absl::ResourceExhaustedError(context);
  if (code == "40001" || code == "40P01" || code == "55P03") {
    return absl::UnavailableError(StrCat(context, ": a concurrent change won; retry"));
  }
  if (code == "23505") return absl::AlreadyExistsError(context);
  if (code == "XX001" || code == "XX002") {
    return absl::DataLossError(StrCat(context, ": the database is damaged"));
  }
  if (code == "42501") {
    return absl::FailedPreconditionError(
        StrCat(context, ": the database user may not do this"));
  }
  return absl::InternalError(context);
}

// "$1" stays "$1": PostgreSQL's own parameters.
class PostgresConnection final : public SqlConnection {
 public:
  explicit PostgresConnection(PgConn conn) : conn_(std::move(conn)) {}
  SqlDialect dialect() const override { return SqlDialect::kPostgres; }

  Result<std::vector<SqlRow>> Query(std::string_view sql, const std::vector<SqlValue>& params,
                                    std::string_view what) override {
    RETURN_IF_ERROR(Reconnect());
    std::vector<std::string> text(params.size());
    std::vector<const char*> values(params.size(), nullptr);
    std::vector<int> lengths(params.size(), 0), formats(params.size(), 0);
    for (size_t i = 0; i < params.size(); ++i) {
      const SqlValue& p = params[i];
      if (std::holds_alternative<std::monostate>(p)) continue;
      if (const auto* b = std::get_if<SqlBlob>(&p)) {
        text[i] = b->bytes;
        formats[i] = 1;  // binary: the bytes as they are
      } else if (const auto* d = std::get_if<double>(&p)) {
        // 17 significant digits: the double exactly, as text.
        char buffer[40];
        std::snprintf(buffer, sizeof buffer, "%.17g", *d);
        text[i] = buffer;
      } else {
        text[i] = SqlText(p);
      }
      values[i] = text[i].data();
      lengths[i] = static_cast<int>(text[i].size());
    }
    const std::string statement(sql);
    PgResult result(PQexecParams(conn_.get(), statement.c_str(), static_cast<int>(params.size()),
                                 nullptr, values.data(), lengths.data(), formats.data(), 0));
    const ExecStatusType status = PQresultStatus(result.get());
    if (status != PGRES_TUPLES_OK && status != PGRES_COMMAND_OK) {
      return PostgresError(result.get(), conn_.get(), what);
    }
    std::vector<SqlRow> rows(PQntuples(result.get()));
    const int columns = PQnfields(result.get());
    for (size_t r = 0; r < rows.size(); ++r) {
      rows[r].reserve(columns);
      for (int c = 0; c < columns; ++c) rows[r].push_back(Cell(result.get(), int(r), c));
    }
    return rows;
  }

  Status ExecScript(const std::string& sql, std::string_view what) override {
    RETURN_IF_ERROR(Reconnect());
    PgResult result(PQexec(conn_.get(), sql.c_str()));
    if (PQresultStatus(result.get()) != PGRES_COMMAND_OK &&
        PQresultStatus(result.get()) != PGRES_TUPLES_OK) {
      return PostgresError(result.get(), conn_.get(), what);
    }
    return absl::OkStatus();
  }
  Status Begin(std::string_view what) override {
    return ExecScript("BEGIN", StrCat("start to ", what));
  }
  Status Commit(std::string_view what) override { return ExecScript("COMMIT", what); }
  void Rollback() override {
    if (PQstatus(conn_.get()) == CONNECTION_OK) PgResult(PQexec(conn_.get(), "ROLLBACK"));
  }
  Status LockSchema() override {
    // Any constant: every vpm-server migrating this database takes it.
    return ExecScript("SELECT pg_advisory_xact_lock(7366511); "
                      "CREATE TABLE IF NOT EXISTS vpm_schema_version(version INTEGER NOT NULL)",
                      "lock the schema");
  }
  Result<int> SchemaVersion() override {
    ASSIGN_OR_RETURN(std::vector<SqlRow> rows,
                     Query("SELECT coalesce(max(version), 0) FROM vpm_schema_version", {},
                           "read the schema version"));
    return rows.empty() ? 0 : static_cast<int>(SqlInt(rows[0][0]));
  }
  std::string SetSchemaVersionSql(int version) const override {
    return StrCat("DELETE FROM vpm_schema_version; INSERT INTO vpm_schema_version VALUES(",
                  version, ");");
  }
  std::string_view LockRowSuffix() const override { return " FOR UPDATE"; }

 private:
  // A dropped connection (the database restarted, a network blip) is
  // opened again before the next statement; outside a transaction only,
  // as a transaction's work died with its connection.
  Status Reconnect() {
    if (PQstatus(conn_.get()) == CONNECTION_OK) return absl::OkStatus();
    PQreset(conn_.get());
    if (PQstatus(conn_.get()) == CONNECTION_OK) return absl::OkStatus();
    return PostgresError(nullptr, conn_.get(), "reach the database");
  }

  static SqlValue Cell(const PGresult* result, int row, int column) {
    if (PQgetisnull(result, row, column)) return std::monostate{};
    const char* value = PQgetvalue(result, row, column);
    switch (PQftype(result, column)) {
      case kInt8Oid:
      case kInt4Oid:
        return static_cast<int64_t>(std::strtoll(value, nullptr, 10));
      case kFloat8Oid:
        return std::strtod(value, nullptr);
      case kByteaOid: {
        size_t length = 0;
        unsigned char* bytes =
            PQunescapeBytea(reinterpret_cast<const unsigned char*>(value), &length);
        SqlBlob blob{std::string(reinterpret_cast<const char*>(bytes), length)};
        PQfreemem(bytes);
        return blob;
      }
      default:
        return std::string(value, PQgetlength(result, row, column));
    }
  }

  PgConn conn_;
};

}  // namespace

Result<std::unique_ptr<SqlConnection>> OpenPostgresConnection(const std::string& conninfo) {
  char* error = nullptr;
  PQconninfoOption* options = PQconninfoParse(conninfo.c_str(), &error);
  if (options == nullptr) {
    const std::string reason = error != nullptr ? error : "malformed";
    PQfreemem(error);
    return absl::InvalidArgumentError(
        StrCat("--state: not a PostgreSQL connection string (", reason, ")"));
  }
  bool has_password = false;
  for (PQconninfoOption* o = options; o->keyword != nullptr; ++o) {
    if (std::strcmp(o->keyword, "password") == 0 && o->val != nullptr && o->val[0] != '\0') {
      has_password = true;
    }
  }
  PQconninfoFree(options);
  if (has_password) {
    return absl::InvalidArgumentError(
        "--state: the connection string holds a password; put it in a libpq password file "
        "(PGPASSFILE or ~/.pgpass) instead, so that it is in neither argv nor a log");
  }
  PgConn conn(PQconnectdb(conninfo.c_str()));
  if (PQstatus(conn.get()) != CONNECTION_OK) {
    std::string detail = PQerrorMessage(conn.get());
    while (!detail.empty() && (detail.back() == '\n' || detail.back() == ' ')) detail.pop_back();
    return absl::UnavailableError(
        StrCat("case store: cannot connect to PostgreSQL (", detail, ")"));
  }
  PgResult quiet(PQexec(conn.get(), "SET client_min_messages = warning"));
  return std::unique_ptr<SqlConnection>(new PostgresConnection(std::move(conn)));
}

Result<std::unique_ptr<CaseStore>> OpenPostgresCaseStore(const std::string& conninfo) {
  ASSIGN_OR_RETURN(std::unique_ptr<SqlConnection> connection, OpenPostgresConnection(conninfo));
  return MakeSqlCaseStore(std::move(connection));
}

}  // namespace vpm::cases
