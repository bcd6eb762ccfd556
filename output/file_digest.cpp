#include "output/file_digest.hpp"

#include <openssl/evp.h>

#include <cstdio>
#include <memory>

#include "core/error.hpp"
#include "core/text.hpp"

namespace softbake {

namespace {

using DigestContext = std::unique_ptr<EVP_MD_CTX, void (*)(EVP_MD_CTX*)>;

DigestContext startSha256() {
  DigestContext context(EVP_MD_CTX_new(), &EVP_MD_CTX_free);
  if (!context || EVP_DigestInit_ex(context.get(), EVP_sha256(), nullptr) != 1)
    throw Error("OpenSSL could not start a SHA-256");
  return context;
}

std::string finish(EVP_MD_CTX* context) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_DigestFinal_ex(context, digest, &length);
  return std::string(reinterpret_cast<const char*>(digest), length);
}

}  // namespace

std::string sha256(std::string_view bytes) {
  const DigestContext context = startSha256();
  EVP_DigestUpdate(context.get(), bytes.data(), bytes.size());
  return finish(context.get());
}

std::string sha256OfFile(const std::filesystem::path& path) {
  const std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) throw Error(cat(path.string(), ": cannot read the file to take its SHA-256"));
  const DigestContext context = startSha256();
  unsigned char chunk[1 << 16];
  std::size_t read = 0;
  while ((read = std::fread(chunk, 1, sizeof chunk, file.get())) > 0)
    EVP_DigestUpdate(context.get(), chunk, read);
  if (std::ferror(file.get()))
    throw Error(cat(path.string(), ": cannot read the file to take its SHA-256"));
  static constexpr char kHex[] = "0123456789abcdef";
  std::string hex;
  for (const char byte : finish(context.get())) {
    hex += kHex[std::uint8_t(byte) >> 4];
    hex += kHex[std::uint8_t(byte) & 15];
  }
  return hex;
}

}  // namespace softbake
