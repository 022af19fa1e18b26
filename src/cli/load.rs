//! The load step's reading of the inputs a report names in its provenance: each
//! file read once here, its size and SHA-256 passed on to the renderers.

use std::path::Path;

use rocklab::facade::Study;
use rocklab::ingest::Campaign;
use rocklab::report::campaign::Sources;
use rocklab::report::InputFile;

/// One input file as read now.
pub fn input(role: &str, path: &Path) -> InputFile {
    InputFile::from_reader(role, path, std::fs::File::open(path))
}

/// The manifest (its text and facts) and every test's log.
pub fn campaign_sources(c: &Campaign) -> Sources {
    let bytes = std::fs::read(&c.manifest_path);
    let manifest = bytes.as_ref().map(|b| String::from_utf8_lossy(b).into_owned()).unwrap_or_default();
    let mut files = vec![InputFile::new("manifest", &c.manifest_path, bytes)];
    files.extend(c.tests.iter().map(|t| input(&t.id, &t.file)));
    Sources { manifest, files }
}

/// The study file, the block file it names, and every record.
pub fn study_inputs(study: &Study) -> Vec<InputFile> {
    let mut files = vec![input("study", &study.path), input("block", &study.block_path)];
    files.extend(study.records.iter().map(|r| input(&r.name, &r.record.path)));
    files
}
