#include "elf_file.hpp"

#include <elf.h>

#include <cerrno>
#include <cstddef>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace fba::detail {

namespace fs = std::filesystem;

namespace {

std::string machine_name(unsigned machine) {
  switch (machine) {
    case EM_X86_64: return "x86-64";
    case EM_386: return "x86 (32-bit)";
    case EM_AARCH64: return "aarch64";
    case EM_ARM: return "arm (32-bit)";
    case EM_RISCV: return "riscv";
    case EM_PPC64: return "ppc64";
    case EM_PPC: return "ppc (32-bit)";
    case EM_S390: return "s390x";
    case EM_MIPS: return "mips";
#ifdef EM_LOONGARCH
    case EM_LOONGARCH: return "loongarch";
#endif
    default: return "ELF machine " + std::to_string(machine);
  }
}

struct Reader {
  std::ifstream in;
  std::uintmax_t size;
  // Reads n bytes at offset; false when they are not all in the file.
  bool read(std::uint64_t offset, void* out, std::size_t n) {
    if (offset > size || n > size - offset) return false;
    in.seekg(static_cast<std::streamoff>(offset));
    in.read(static_cast<char*>(out), static_cast<std::streamsize>(n));
    return static_cast<std::size_t>(in.gcount()) == n;
  }
};

// This process's own ELF header: the class and machine a plugin must match.
const Elf64_Ehdr& own_header() {
  static const Elf64_Ehdr header = [] {
    Elf64_Ehdr h{};
    std::ifstream in("/proc/self/exe", std::ios::binary);
    in.read(reinterpret_cast<char*>(&h), sizeof h);
    return h;
  }();
  return header;
}

std::string truncated(std::uintmax_t size, const std::string& what, std::uint64_t needed) {
  return "is truncated: " + what + " needs the file's bytes up to " + std::to_string(needed) + ", but it has only " +
         std::to_string(size) + " bytes (an interrupted copy or build?)";
}

}  // namespace

std::string not_a_regular_file(const fs::path& file) {
  std::error_code ec;
  const auto link = fs::symlink_status(file, ec);
  if (ec || !fs::exists(link)) return "no such file";
  const auto st = fs::status(file, ec);
  if (fs::is_symlink(link)) {
    if (ec && ec.value() == ELOOP) return "is a symbolic link that loops (too many levels of symbolic links)";
    if (ec || !fs::exists(st)) {
      std::error_code ec2;
      return "is a dangling symbolic link to '" + fs::read_symlink(file, ec2).string() + "' (nothing there)";
    }
  }
  if (ec) return "cannot be read: " + ec.message();
  if (fs::is_directory(st)) return "is a directory, not a plugin file";
  if (!fs::is_regular_file(st)) return "is not a regular file (a device, pipe or socket?)";
  return "";
}

ElfFile check_elf(const fs::path& file) {
  if (auto why = not_a_regular_file(file); !why.empty()) throw std::runtime_error(why);
  Reader r{std::ifstream(file, std::ios::binary), 0};
  std::error_code ec;
  r.size = fs::file_size(file, ec);
  if (ec || !r.in) throw std::runtime_error("cannot be opened: " + std::string(std::strerror(errno)));
  if (r.size == 0) throw std::runtime_error("is an empty file (0 bytes), not a shared object");

  unsigned char ident[EI_NIDENT] = {};
  const bool whole_ident = r.read(0, ident, std::min<std::uintmax_t>(r.size, EI_NIDENT));
  if (std::memcmp(ident, ELFMAG, std::min<std::size_t>(SELFMAG, r.size)) != 0)
    throw std::runtime_error("is not an ELF shared object (no ELF magic number at its start)");
  if (!whole_ident) throw std::runtime_error(truncated(r.size, "the ELF identification", EI_NIDENT));
  const Elf64_Ehdr& own = own_header();
  if (ident[EI_CLASS] != own.e_ident[EI_CLASS]) {
    // e_machine is at the same place in 32- and 64-bit headers: say which architecture it is for.
    std::string built_for;
    unsigned char m[2];
    if (r.size >= offsetof(Elf64_Ehdr, e_machine) + 2 && r.read(offsetof(Elf64_Ehdr, e_machine), m, 2))
      built_for = ", built for " + machine_name(ident[EI_DATA] == ELFDATA2MSB ? (m[0] << 8 | m[1]) : (m[1] << 8 | m[0]));
    throw std::runtime_error(std::string("is a ") + (ident[EI_CLASS] == ELFCLASS32 ? "32" : "non-64") + "-bit ELF file" +
                             built_for + "; this fba is a 64-bit program for " + machine_name(own.e_machine));
  }
  if (ident[EI_DATA] != own.e_ident[EI_DATA])
    throw std::runtime_error("has the other byte order (endianness) than this machine");
  if (r.size < sizeof(Elf64_Ehdr)) throw std::runtime_error(truncated(r.size, "the ELF header", sizeof(Elf64_Ehdr)));
  Elf64_Ehdr h{};
  r.read(0, &h, sizeof h);
  if (h.e_machine != own.e_machine)
    throw std::runtime_error("was built for " + machine_name(h.e_machine) + "; this fba runs on " + machine_name(own.e_machine));
  if (h.e_type != ET_DYN)
    throw std::runtime_error("is not a shared object (ELF type " + std::to_string(h.e_type) + (h.e_type == ET_REL ? ", an object file" : "") +
                             "): build it with fba_add_plugin");
  if (h.e_phentsize != sizeof(Elf64_Phdr)) throw std::runtime_error("has a malformed ELF header (program header size)");

  ElfFile out;
  out.size = r.size;
  const std::uint64_t ph_end = h.e_phoff + std::uint64_t{h.e_phnum} * sizeof(Elf64_Phdr);
  if (ph_end > r.size) throw std::runtime_error(truncated(r.size, "the program header table", ph_end));
  std::vector<Elf64_Phdr> ph(h.e_phnum);
  r.read(h.e_phoff, ph.data(), ph.size() * sizeof(Elf64_Phdr));
  for (std::size_t i = 0; i < ph.size(); ++i) {
    const auto& p = ph[i];
    const std::uint64_t end = p.p_offset + p.p_filesz;
    if (end < p.p_offset || end > r.size) throw std::runtime_error(truncated(r.size, "segment " + std::to_string(i), end));
  }
  // The GNU build id identifies this exact build; the manifest records it, so a manifest left
  // beside a rebuilt plugin is noticed.
  for (const auto& p : ph) {
    if (p.p_type != PT_NOTE || p.p_filesz > (1u << 20)) continue;
    std::vector<unsigned char> notes(p.p_filesz);
    r.read(p.p_offset, notes.data(), notes.size());
    const auto align4 = [](std::size_t n) { return (n + 3) & ~std::size_t{3}; };
    for (std::size_t at = 0; at + sizeof(Elf64_Nhdr) <= notes.size();) {
      Elf64_Nhdr n;
      std::memcpy(&n, notes.data() + at, sizeof n);
      const std::size_t name_at = at + sizeof n, desc_at = name_at + align4(n.n_namesz);
      if (desc_at > notes.size() || n.n_descsz > notes.size() - desc_at) break;
      if (n.n_type == NT_GNU_BUILD_ID && n.n_namesz == 4 && std::memcmp(notes.data() + name_at, "GNU", 4) == 0) {
        std::ostringstream hex;
        for (std::size_t i = 0; i < n.n_descsz; ++i) {
          static const char digits[] = "0123456789abcdef";
          hex << digits[notes[desc_at + i] >> 4] << digits[notes[desc_at + i] & 15];
        }
        out.build_id = hex.str();
      }
      at = desc_at + align4(n.n_descsz);
    }
  }
  return out;
}

}  // namespace fba::detail
