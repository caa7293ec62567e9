// Generic groups of the store: H5Table (small datasets and attributes written or read at once,
// used for /branch, /bifurcations and /validation) and WriteGroup (numeric attributes).
#include <fmt/format.h>

#include "io/hdf5_store_impl.hpp"
#include "vibro/scene_file.hpp"

namespace vibro {

const H5Table::Array* H5Table::Find(const std::string& name) const {
  for (const auto& a : arrays)
    if (a.name == name) return &a;
  return nullptr;
}

void Hdf5Store::WriteTable(const std::string& group, const H5Table& t) {
  impl_->Sync();
  const h5::Handle g = h5::CreateGroup(impl_->file.get(), group);
  for (const auto& a : t.arrays) {
    const std::vector<h5::Size> dims(a.dims.begin(), a.dims.end());
    if (a.type == 'u') {
      std::vector<std::uint8_t> v(a.data.begin(), a.data.end());
      h5::WriteDataset(g.get(), a.name, h5::Type::U8(), v.data(), dims);
    } else if (a.type == 'i') {
      std::vector<std::int64_t> v(a.data.begin(), a.data.end());
      h5::WriteDataset(g.get(), a.name, h5::Type::I64(), v.data(), dims);
    } else {
      h5::WriteDataset(g.get(), a.name, h5::Type::F64(), a.data.data(), dims);
    }
  }
  for (const auto& [name, v] : t.strings) h5::WriteStrings(g.get(), name, v);
  for (const auto& [name, v] : t.text) h5::WriteString(g.get(), name, v);
  for (const auto& [name, v] : t.integers) h5::WriteInt(g.get(), name, v);
}

void Hdf5Store::WriteGroup(const std::string& group,
                           const std::vector<std::pair<std::string, std::vector<double>>>& values) {
  impl_->Sync();
  const h5::Handle g = h5::OpenOrCreateGroup(impl_->file.get(), group);
  for (const auto& [name, v] : values) h5::WriteDoubles(g.get(), name, v);
}

H5Table ReadTable(const std::string& path, const std::string& group) {
  h5::Silence();
  const h5::Handle file = h5::OpenFile(path, false);
  if (!file) throw store::CannotOpen(path);
  if (!h5::Exists(file.get(), group)) throw InputError({fmt::format("{}: no group {} in this file", path, group)});
  const h5::Handle g = h5::OpenGroup(file.get(), group);
  H5Table t;
  for (const auto& name : h5::DatasetNames(g.get())) {
    if (h5::IsStringDataset(g.get(), name)) {
      t.strings.emplace_back(name, h5::ReadDatasetStrings(g.get(), name));
    } else {
      const auto dims = *h5::DatasetShape(g.get(), name);
      t.arrays.push_back({name, std::vector<size_t>(dims.begin(), dims.end()), h5::ReadDatasetDoubles(g.get(), name)});
    }
  }
  for (const auto& name : h5::AttrNames(g.get())) {
    const h5::Class c = h5::AttrClass(g.get(), name);
    if (c == h5::Class::kString)
      t.text.emplace_back(name, h5::ReadString(g.get(), name));
    else if (c == h5::Class::kInteger)
      t.integers.emplace_back(name, h5::ReadInt(g.get(), name).value_or(0));
  }
  return t;
}

}  // namespace vibro
