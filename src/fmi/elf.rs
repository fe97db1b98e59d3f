//! An FMU's binary checked from its bytes before anything maps it into this process: a 64-bit little-endian x86-64
//! ELF shared library, whose program headers and load segments lie inside the file (the dynamic loader maps a
//! segment past the end of a cut-short file, and the first touch of it kills the process with SIGBUS), and whose
//! dynamic symbol table exports every function the importer resolves. Each problem is said in words, with the fix.

use std::path::Path;

/// The ELF identification and header fields read here (ELF-64, little-endian).
const MAGIC: &[u8; 4] = b"\x7fELF";
const HEADER_LEN: usize = 64;
const CLASS_64: u8 = 2;
const DATA_LITTLE_ENDIAN: u8 = 1;
const TYPE_SHARED: u16 = 3;
const MACHINE_X86_64: u16 = 62;
const SEGMENT_LOAD: u32 = 1;
const SEGMENT_DYNAMIC: u32 = 2;
const SECTION_DYNSYM: u32 = 11;
const SYMBOL_LEN: usize = 24;

/// Read `binary` (`inside` the archive: how errors name it) and check it can be loaded safely and exports
/// `symbols`, the functions of `standard`; the error names the binary and the fix.
pub(crate) fn check(binary: &Path, inside: &str, standard: &str, symbols: &[&str]) -> Result<(), String> {
    let bytes = std::fs::read(binary).map_err(|e| format!("its binary {inside} cannot be read: {e}"))?;
    check_bytes(&bytes, standard, symbols).map_err(|problem| format!("its binary {inside} {problem}"))
}

/// What is wrong with the bytes of a binary, as the end of a sentence starting with its name.
fn check_bytes(bytes: &[u8], standard: &str, symbols: &[&str]) -> Result<(), String> {
    let re_export = "re-export the FMU for Linux x86-64";
    if bytes.len() < HEADER_LEN || &bytes[..4] != MAGIC {
        return Err(match bytes.starts_with(MAGIC) {
            true => format!("is cut short: {} bytes, less than an ELF header; copy the FMU again", bytes.len()),
            false => format!("is not an ELF shared library (a Linux binary starts with \\x7fELF); {re_export}"),
        });
    }
    match bytes[4] {
        CLASS_64 => {}
        1 => return Err(format!("is a 32-bit binary (ELFCLASS32), which a 64-bit process cannot load; {re_export}")),
        other => return Err(format!("has ELF class {other}, neither 32- nor 64-bit; {re_export}")),
    }
    if bytes[5] != DATA_LITTLE_ENDIAN {
        return Err(format!("is big-endian, not the little-endian code of an x86-64; {re_export}"));
    }
    let elf_type = u16_at(bytes, 16);
    if elf_type != TYPE_SHARED {
        return Err(format!("is an ELF file of type {elf_type}, not a shared library (type 3); {re_export}"));
    }
    let machine = u16_at(bytes, 18);
    if machine != MACHINE_X86_64 {
        return Err(format!("is built for {}, not x86-64 (machine 62); {re_export}", machine_name(machine)));
    }
    check_segments(bytes)?;
    check_symbols(bytes, standard, symbols)
}

fn u16_at(bytes: &[u8], at: usize) -> u16 {
    u16::from_le_bytes(bytes[at..at + 2].try_into().expect("2 bytes"))
}

fn u32_at(bytes: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"))
}

fn u64_at(bytes: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes"))
}

fn machine_name(machine: u16) -> String {
    match machine {
        3 => "32-bit x86 (machine 3)".into(),
        40 => "32-bit ARM (machine 40)".into(),
        183 => "AArch64 (machine 183)".into(),
        243 => "RISC-V (machine 243)".into(),
        other => format!("machine {other}"),
    }
}

/// `count` entries of `size` bytes from `offset`, if they lie inside the file.
fn table(bytes: &[u8], offset: u64, size: u64, count: u64) -> Option<std::ops::Range<usize>> {
    let end = size.checked_mul(count)?.checked_add(offset)?;
    (end <= bytes.len() as u64).then(|| offset as usize..end as usize)
}

fn cut_short(bytes: &[u8], what: &str, end: u64) -> String {
    format!(
        "is cut short: its {what} ends at byte {end} but the file has {} bytes (a truncated copy or a broken \
         archive); copy or export the FMU again",
        bytes.len()
    )
}

/// The program headers, and every loaded or dynamic segment, inside the file.
fn check_segments(bytes: &[u8]) -> Result<(), String> {
    let (offset, size, count) = (u64_at(bytes, 32), u64::from(u16_at(bytes, 54)), u64::from(u16_at(bytes, 56)));
    let Some(headers) = table(bytes, offset, size, count).filter(|_| size >= 56) else {
        return Err(cut_short(bytes, "program header table", offset.saturating_add(size.saturating_mul(count))));
    };
    for (k, header) in bytes[headers].chunks_exact(size as usize).enumerate() {
        let kind = u32_at(header, 0);
        if kind != SEGMENT_LOAD && kind != SEGMENT_DYNAMIC {
            continue;
        }
        let (file_offset, file_size) = (u64_at(header, 8), u64_at(header, 32));
        if table(bytes, file_offset, file_size, 1).is_none() {
            return Err(cut_short(bytes, &format!("segment {k}"), file_offset.saturating_add(file_size)));
        }
    }
    Ok(())
}

/// Every name in `symbols` defined in the dynamic symbol table. A binary without section headers (stripped of
/// them, which the loader does not need) is not checked here: the loader's lookup names a missing function then.
fn check_symbols(bytes: &[u8], standard: &str, symbols: &[&str]) -> Result<(), String> {
    let (offset, size, count) = (u64_at(bytes, 40), u64::from(u16_at(bytes, 58)), u64::from(u16_at(bytes, 60)));
    if offset == 0 || count == 0 {
        return Ok(());
    }
    let Some(headers) = table(bytes, offset, size, count).filter(|_| size >= 64) else {
        return Err(cut_short(bytes, "section header table", offset.saturating_add(size.saturating_mul(count))));
    };
    let sections: Vec<&[u8]> = bytes[headers].chunks_exact(size as usize).collect();
    let Some(dynsym) = sections.iter().find(|s| u32_at(s, 4) == SECTION_DYNSYM) else {
        return Err(format!(
            "exports no dynamic symbols at all, so none of the {standard} functions; rebuild it as a \
                            shared library that exports them"
        ));
    };
    let range = |s: &[u8]| table(bytes, u64_at(s, 24), u64_at(s, 32), 1);
    let strings = sections.get(u32_at(dynsym, 40) as usize).and_then(|s| range(s));
    let (Some(symbol_bytes), Some(strings)) = (range(dynsym), strings) else {
        return Err(cut_short(bytes, "dynamic symbol table", u64_at(dynsym, 24).saturating_add(u64_at(dynsym, 32))));
    };
    let strings = &bytes[strings];
    let defined: std::collections::HashSet<&[u8]> = bytes[symbol_bytes]
        .chunks_exact(SYMBOL_LEN)
        .filter(|symbol| u16_at(symbol, 6) != 0)
        .filter_map(|symbol| {
            let name = strings.get(u32_at(symbol, 0) as usize..)?;
            Some(&name[..name.iter().position(|&b| b == 0)?])
        })
        .collect();
    let missing: Vec<&str> = symbols.iter().copied().filter(|s| !defined.contains(s.as_bytes())).collect();
    match missing.as_slice() {
        [] => Ok(()),
        [one] => Err(format!("lacks the {standard} function {one}; an FMU's binary exports every one it declares")),
        many => Err(format!(
            "lacks the {standard} functions {}; an FMU's binary exports every one it declares",
            many.join(", ")
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// This test binary itself: a 64-bit x86-64 ELF executable, position-independent (Rust's default on Linux), so
    /// of type 3 as a shared library is, with a dynamic symbol table.
    fn own_bytes() -> Vec<u8> {
        let bytes = std::fs::read(std::env::current_exe().unwrap()).unwrap();
        assert_eq!(u16_at(&bytes, 16), TYPE_SHARED, "the test binary is not position-independent");
        bytes
    }

    #[test]
    fn a_whole_binary_passes_and_its_missing_function_is_named() {
        let bytes = own_bytes();
        assert_eq!(check_bytes(&bytes, "FMI 2.0", &[]), Ok(()));
        let e = check_bytes(&bytes, "FMI 2.0", &["fmi2NoSuchFunction"]).unwrap_err();
        assert!(e.contains("lacks the FMI 2.0 function fmi2NoSuchFunction"), "{e}");
    }

    #[test]
    fn cut_short_wrong_class_machine_and_not_elf_are_refused_in_words() {
        let bytes = own_bytes();
        let e = check_bytes(&bytes[..bytes.len() / 2], "FMI 2.0", &[]).unwrap_err();
        assert!(
            e.starts_with("is cut short: its ") && e.contains(&format!("file has {} bytes", bytes.len() / 2)),
            "{e}"
        );
        assert!(check_bytes(&bytes[..40], "FMI 2.0", &[]).unwrap_err().contains("less than an ELF header"));
        let mut class32 = bytes.clone();
        class32[4] = 1;
        assert!(check_bytes(&class32, "FMI 2.0", &[]).unwrap_err().contains("32-bit binary (ELFCLASS32)"));
        let mut arm = bytes.clone();
        arm[18..20].copy_from_slice(&183u16.to_le_bytes());
        assert!(check_bytes(&arm, "FMI 2.0", &[]).unwrap_err().contains("built for AArch64 (machine 183)"));
        let e =
            check_bytes(b"MZ this is a Windows DLL, long enough to be an ELF header if it were one......", "x", &[]);
        assert!(e.unwrap_err().contains("not an ELF shared library"));
    }
}
