//! Phase 1: read the root files and everything they `use`, each file once,
//! and parse them. `use` paths are relative to the using file; a cycle is
//! reported at the `use` that closes it.

use crate::error::Error;
use crate::source::{FileId, Loader, Loc, SourceMap, normalize};
use packwright_grammar::ast;
use std::path::{Path, PathBuf};

/// The parsed files, dependencies before the files that use them.
pub struct Loaded {
    pub sources: SourceMap,
    pub files: Vec<(FileId, ast::File)>,
    pub errors: Vec<Error>,
    /// Each loaded file's [`Loader::identity`], where the loader gives one.
    identities: Vec<(PathBuf, FileId)>,
}

pub fn load(loader: &dyn Loader, roots: &[PathBuf]) -> Loaded {
    let mut state = Loaded {
        sources: SourceMap::default(),
        files: Vec::new(),
        errors: Vec::new(),
        identities: Vec::new(),
    };
    let mut stack = Vec::new();
    for root in roots {
        visit(loader, &mut state, root, None, &mut stack);
    }
    state
}

fn visit(
    loader: &dyn Loader,
    state: &mut Loaded,
    path: &Path,
    used_at: Option<Loc>,
    stack: &mut Vec<FileId>,
) {
    let path = normalize(path);
    let identity = loader.identity(&path);
    let same = identity
        .as_ref()
        .and_then(|i| state.identities.iter().find(|(j, _)| j == i))
        .map(|&(_, id)| id);
    if let Some(id) = state.sources.find(&path).or(same) {
        if let (Some(pos), Some(at)) = (stack.iter().position(|s| *s == id), used_at) {
            let chain = stack[pos..]
                .iter()
                .chain(std::iter::once(&id))
                .filter_map(|f| state.sources.get(*f))
                .map(|f| f.path.display().to_string())
                .collect::<Vec<_>>()
                .join(" -> ");
            state.errors.push(Error::UseCycle { at, chain });
        }
        return;
    }
    let read = match used_at {
        Some(_) => loader.read_named(&path),
        None => loader.read(&path),
    };
    let text = match read {
        Ok(text) => text,
        Err(reason) => {
            state.errors.push(match used_at {
                Some(at) => Error::UseMissing {
                    at,
                    path: path.display().to_string(),
                    reason,
                },
                None => Error::Read { path, reason },
            });
            return;
        }
    };
    let id = state.sources.add(path.clone(), text);
    if let Some(identity) = identity {
        state.identities.push((identity, id));
    }
    let parsed = match state.sources.get(id) {
        Some(f) => packwright_grammar::parse(&f.text),
        None => return,
    };
    let file = match parsed {
        Ok(file) => file,
        Err(errors) => {
            state
                .errors
                .extend(errors.into_iter().map(|error| Error::Syntax {
                    at: Loc::new(id, error.span()),
                    error,
                }));
            return;
        }
    };
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    stack.push(id);
    for item in &file.items {
        if let ast::Item::Use(u) = item {
            visit(
                loader,
                state,
                &dir.join(&u.path.value),
                Some(Loc::new(id, u.path.span)),
                stack,
            );
        }
    }
    stack.pop();
    state.files.push((id, file));
}
