//! The length of every function of one file, test code left out.

use std::path::{Path, PathBuf};

use syn::punctuated::Punctuated;
use syn::visit::{self, Visit};
use syn::{Attribute, Block, Meta, Signature, Token};

use crate::LintError;

/// One function (free function, method, or a trait's provided method) and its
/// length.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Function {
    /// The file, relative to the workspace's root, `/`-separated.
    pub path: String,
    /// The line of its `fn` keyword (1-based).
    pub line: usize,
    /// Its name, `Type::name` for a method (`Trait::name` for a trait's
    /// provided method); a function inside a function by its own name.
    pub name: String,
    /// From the `fn` keyword's line to the closing brace's, both counted
    /// \[lines\]; attributes and doc comments before it do not count.
    pub lines: usize,
}

/// An out-of-line module (`mod name;`) a file declares.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ModuleFile {
    /// The module's file, where it exists (`name.rs`, else `name/mod.rs`,
    /// or the file its `#[path]` names).
    pub path: PathBuf,
    /// Whether the module is test code: `#[cfg(test)]` on it or on a module
    /// around it.
    pub test: bool,
}

/// What one file holds: its functions outside test code, and the files of
/// the modules it declares out of line.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FileScan {
    /// Every function outside test code, in the file's order.
    pub functions: Vec<Function>,
    /// Every out-of-line module whose file exists.
    pub modules: Vec<ModuleFile>,
}

/// Parses `file` (a path under `root`) and measures its functions.
pub fn scan_file(root: &Path, file: &Path) -> Result<FileScan, LintError> {
    let source = std::fs::read_to_string(file).map_err(|source| LintError::Io {
        path: file.to_path_buf(),
        source,
    })?;
    let path = file
        .strip_prefix(root)
        .unwrap_or(file)
        .components()
        .map(|c| c.as_os_str().to_string_lossy())
        .collect::<Vec<_>>()
        .join("/");
    scan_source(&path, file, &source)
}

/// Measures the functions of `source`, the text of `file` (shown as `path`).
pub fn scan_source(path: &str, file: &Path, source: &str) -> Result<FileScan, LintError> {
    let syntax = syn::parse_file(source).map_err(|e| LintError::Parse {
        path: file.to_path_buf(),
        line: e.span().start().line,
        message: e.to_string(),
    })?;
    let dir = file.parent().unwrap_or(Path::new("")).to_path_buf();
    let mut scan = Scan {
        path,
        dir: dir.clone(),
        module_dir: module_dir(file, &dir),
        owners: Vec::new(),
        in_test: false,
        found: FileScan::default(),
    };
    scan.visit_file(&syntax);
    Ok(scan.found)
}

/// Where the files of `file`'s child modules live: beside it for a crate
/// root or a `mod.rs`, in a directory named after it otherwise.
fn module_dir(file: &Path, dir: &Path) -> PathBuf {
    let name = file.file_name().map(|n| n.to_string_lossy().into_owned());
    let parent = dir.file_name().map(|n| n.to_string_lossy().into_owned());
    let root_like = matches!(
        name.as_deref(),
        Some("lib.rs" | "main.rs" | "mod.rs" | "build.rs")
    ) || matches!(parent.as_deref(), Some("bin" | "examples"));
    match file.file_stem() {
        Some(stem) if !root_like => dir.join(stem),
        _ => dir.to_path_buf(),
    }
}

/// Whether `attrs` mark test code: `#[test]`, `#[bench]` (or an attribute
/// ending so, `#[tokio::test]`), or a `#[cfg]` true only under test.
fn is_test(attrs: &[Attribute]) -> bool {
    attrs.iter().any(|attr| {
        let last = attr.path().segments.last().map(|s| s.ident.to_string());
        if matches!(last.as_deref(), Some("test" | "bench")) {
            return true;
        }
        attr.path().is_ident("cfg") && attr.parse_args::<Meta>().is_ok_and(|m| test_only(&m))
    })
}

/// Whether a `cfg` predicate holds only under test: `test`, an `all(…)` with
/// such a predicate, an `any(…)` of only such predicates.
fn test_only(predicate: &Meta) -> bool {
    let Meta::List(list) = predicate else {
        return predicate.path().is_ident("test");
    };
    let Ok(inner) = list.parse_args_with(Punctuated::<Meta, Token![,]>::parse_terminated) else {
        return false;
    };
    if list.path.is_ident("all") {
        inner.iter().any(test_only)
    } else if list.path.is_ident("any") {
        !inner.is_empty() && inner.iter().all(test_only)
    } else {
        false
    }
}

/// The `#[path = "…"]` of a module, if any.
fn path_attribute(attrs: &[Attribute]) -> Option<String> {
    attrs.iter().find_map(|attr| match &attr.meta {
        Meta::NameValue(nv) if nv.path.is_ident("path") => match &nv.value {
            syn::Expr::Lit(syn::ExprLit {
                lit: syn::Lit::Str(s),
                ..
            }) => Some(s.value()),
            _ => None,
        },
        _ => None,
    })
}

/// The name a method's owner goes by: the last segment of its type's path.
fn type_name(ty: &syn::Type) -> String {
    match ty {
        syn::Type::Path(p) => p
            .path
            .segments
            .last()
            .map_or_else(|| "_".to_owned(), |s| s.ident.to_string()),
        syn::Type::Reference(r) => type_name(&r.elem),
        _ => "_".to_owned(),
    }
}

/// The visitor: where it stands in the file, and what it found.
struct Scan<'a> {
    path: &'a str,
    /// The directory of the file.
    dir: PathBuf,
    /// Where the files of modules declared at this point live.
    module_dir: PathBuf,
    /// The types or traits whose items are being visited, innermost last.
    owners: Vec<String>,
    /// Inside test code.
    in_test: bool,
    found: FileScan,
}

impl Scan<'_> {
    /// Records a function (unless test code) and visits its body with
    /// `in_test` set for a test function.
    fn function(&mut self, attrs: &[Attribute], sig: &Signature, body: Option<&Block>) {
        let test = self.in_test || is_test(attrs);
        if let (false, Some(body)) = (test, body) {
            let line = sig.fn_token.span.start().line;
            let end = body.brace_token.span.close().end().line;
            let name = match self.owners.last() {
                Some(owner) => format!("{owner}::{}", sig.ident),
                None => sig.ident.to_string(),
            };
            self.found.functions.push(Function {
                path: self.path.to_owned(),
                line,
                name,
                lines: end + 1 - line,
            });
        }
        if let Some(body) = body {
            let outer = std::mem::take(&mut self.owners);
            let was_test = std::mem::replace(&mut self.in_test, test);
            self.visit_block(body);
            self.in_test = was_test;
            self.owners = outer;
        }
    }

    /// Visits items owned by `owner` (an impl's type, a trait), `test` if
    /// they are test code.
    fn owned(&mut self, owner: String, test: bool, visit: impl FnOnce(&mut Self)) {
        self.owners.push(owner);
        let was_test = self.in_test;
        self.in_test |= test;
        visit(self);
        self.in_test = was_test;
        self.owners.pop();
    }
}

impl<'ast> Visit<'ast> for Scan<'_> {
    fn visit_item_fn(&mut self, f: &'ast syn::ItemFn) {
        self.function(&f.attrs, &f.sig, Some(&f.block));
    }

    fn visit_impl_item_fn(&mut self, f: &'ast syn::ImplItemFn) {
        self.function(&f.attrs, &f.sig, Some(&f.block));
    }

    fn visit_trait_item_fn(&mut self, f: &'ast syn::TraitItemFn) {
        self.function(&f.attrs, &f.sig, f.default.as_ref());
    }

    fn visit_item_impl(&mut self, i: &'ast syn::ItemImpl) {
        let test = is_test(&i.attrs);
        self.owned(type_name(&i.self_ty), test, |s| {
            visit::visit_item_impl(s, i)
        });
    }

    fn visit_item_trait(&mut self, t: &'ast syn::ItemTrait) {
        let test = is_test(&t.attrs);
        self.owned(t.ident.to_string(), test, |s| visit::visit_item_trait(s, t));
    }

    fn visit_item_mod(&mut self, m: &'ast syn::ItemMod) {
        let test = self.in_test || is_test(&m.attrs);
        let name = m.ident.to_string();
        let Some((_, items)) = &m.content else {
            let candidates = match path_attribute(&m.attrs) {
                Some(path) => vec![self.dir.join(path)],
                None => vec![
                    self.module_dir.join(format!("{name}.rs")),
                    self.module_dir.join(&name).join("mod.rs"),
                ],
            };
            if let Some(path) = candidates.into_iter().find(|c| c.is_file()) {
                self.found.modules.push(ModuleFile { path, test });
            }
            return;
        };
        let outer_dir = self.module_dir.clone();
        self.module_dir = outer_dir.join(&name);
        let outer_owners = std::mem::take(&mut self.owners);
        let was_test = std::mem::replace(&mut self.in_test, test);
        for item in items {
            self.visit_item(item);
        }
        self.in_test = was_test;
        self.owners = outer_owners;
        self.module_dir = outer_dir;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scan(source: &str) -> FileScan {
        scan_source("src/x.rs", Path::new("/nowhere/src/x.rs"), source).unwrap()
    }

    fn lengths(source: &str) -> Vec<(String, usize, usize)> {
        scan(source)
            .functions
            .into_iter()
            .map(|f| (f.name, f.line, f.lines))
            .collect()
    }

    #[test]
    fn measures_from_fn_to_closing_brace() {
        let source = "/// doc\n#[inline]\npub fn a() {\n    let x = 1;\n}\n\nfn b() {}\n";
        assert_eq!(
            lengths(source),
            [("a".to_owned(), 3, 3), ("b".to_owned(), 7, 1)]
        );
    }

    #[test]
    fn names_methods_by_their_type_or_trait() {
        let source = "impl<T> Model<T> {\n fn from_urdf() {}\n}\n\
                      impl Display for &Model {\n fn fmt() {}\n}\n\
                      trait Step {\n fn step() {\n }\n fn required();\n}\n\
                      fn outer() {\n fn inner() {}\n}\n";
        let names: Vec<String> = lengths(source).into_iter().map(|f| f.0).collect();
        assert_eq!(
            names,
            [
                "Model::from_urdf",
                "Model::fmt",
                "Step::step",
                "outer",
                "inner"
            ]
        );
    }

    #[test]
    fn leaves_test_code_out() {
        let source = "#[cfg(test)]\nmod tests {\n fn helper() {}\n #[test]\n fn t() {}\n}\n\
                      #[test]\nfn top() { fn nested() {} }\n\
                      #[tokio::test]\nasync fn t2() {}\n\
                      #[cfg(all(test, feature = \"x\"))]\nfn gated() {}\n\
                      #[cfg(not(test))]\nfn kept() {}\n\
                      #[cfg(any(test, feature = \"x\"))]\nfn also_kept() {}\n\
                      #[cfg(test)]\nimpl A { fn m() {} }\n";
        let names: Vec<String> = lengths(source).into_iter().map(|f| f.0).collect();
        assert_eq!(names, ["kept", "also_kept"]);
    }

    #[test]
    fn finds_out_of_line_modules_and_whether_they_are_tests() {
        let root = std::env::temp_dir().join(format!("phri-lint-mods-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        std::fs::create_dir_all(root.join("src/x/inner")).unwrap();
        for file in ["src/lib.rs", "src/x.rs", "src/x/a.rs", "src/x/inner/b.rs"] {
            std::fs::write(root.join(file), "").unwrap();
        }
        let found = scan_source(
            "src/x.rs",
            &root.join("src/x.rs"),
            "mod a;\n#[cfg(test)]\nmod inner { mod b; }\nmod missing;\n",
        )
        .unwrap();
        let lib = scan_source(
            "src/lib.rs",
            &root.join("src/lib.rs"),
            "#[cfg(test)]\nmod x;",
        )
        .unwrap();
        std::fs::remove_dir_all(&root).unwrap();
        assert_eq!(
            found.modules,
            [
                ModuleFile {
                    path: root.join("src/x/a.rs"),
                    test: false
                },
                ModuleFile {
                    path: root.join("src/x/inner/b.rs"),
                    test: true
                },
            ]
        );
        assert_eq!(
            lib.modules,
            [ModuleFile {
                path: root.join("src/x.rs"),
                test: true
            }]
        );
    }

    #[test]
    fn a_parse_error_names_file_and_line() {
        let err =
            scan_source("src/x.rs", Path::new("src/x.rs"), "fn a() {}\nlet x = 1;\n").unwrap_err();
        assert!(matches!(err, LintError::Parse { line: 2, .. }), "{err}");
    }
}
