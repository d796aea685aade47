//! `#[derive(Describe)]` for Caravan message types: the layout description that
//! `caravan_schemas::describe` gives other languages and tools (size, alignment, and each
//! field's offset and type, all from the compiler), written from the struct's own declaration
//! so that a message type is declared once.
//!
//! ```ignore
//! #[repr(C)]
//! #[derive(Clone, Copy, Debug, ZeroCopySend, PlacementDefault, Serialize, Describe)]
//! #[type_name("my_scenario::Beacon")]
//! pub struct Beacon { pub id: u32, pub _reserved: u32, pub position: Vector3 }
//! ```

use proc_macro::TokenStream;
use quote::quote;
use syn::{Data, DeriveInput, Fields, parse_macro_input};

/// Implements `caravan_schemas::describe::Describe` and `ElementKind` for a `#[repr(C)]`
/// struct with named fields, so that it can be described and used as a field of other
/// described types.
///
/// `#[count(a)]` or `#[count(a, b)]` on an array field: only its first `a` (or `a × b`) items
/// are valid, where `a` and `b` are integer fields of the same struct. Tools show only those.
#[proc_macro_derive(Describe, attributes(count))]
pub fn derive_describe(input: TokenStream) -> TokenStream {
    let input = parse_macro_input!(input as DeriveInput);
    match describe(&input) {
        Ok(tokens) => tokens.into(),
        Err(e) => e.to_compile_error().into(),
    }
}

fn describe(input: &DeriveInput) -> syn::Result<proc_macro2::TokenStream> {
    let ty = &input.ident;
    if !input.generics.params.is_empty() {
        return Err(syn::Error::new_spanned(
            &input.generics,
            "Describe: a message type has no generic parameters",
        ));
    }
    // Offsets only mean something to another language when the layout is C's.
    let repr_c = input.attrs.iter().any(|a| {
        a.path().is_ident("repr")
            && a.parse_nested_meta(|m| {
                if m.path.is_ident("C") {
                    Ok(())
                } else {
                    Err(m.error("other"))
                }
            })
            .is_ok()
    });
    if !repr_c {
        return Err(syn::Error::new_spanned(
            ty,
            "Describe: a message type must be #[repr(C)]",
        ));
    }
    let fields = match &input.data {
        Data::Struct(s) => match &s.fields {
            Fields::Named(named) => &named.named,
            _ => {
                return Err(syn::Error::new_spanned(
                    ty,
                    "Describe: a message type has named fields",
                ));
            }
        },
        _ => {
            return Err(syn::Error::new_spanned(
                ty,
                "Describe: a message type is a struct",
            ));
        }
    };
    let mut pushes = Vec::new();
    for f in fields {
        let name = f.ident.as_ref().expect("named fields");
        let field_ty = &f.ty;
        let mut counts = Vec::new();
        for a in f.attrs.iter().filter(|a| a.path().is_ident("count")) {
            a.parse_nested_meta(|m| {
                let count = m.path.get_ident().ok_or_else(|| {
                    m.error("Describe: #[count(...)] names fields of this struct")
                })?;
                if !fields
                    .iter()
                    .any(|other| other.ident.as_ref() == Some(count))
                {
                    return Err(m.error(format!("Describe: no field '{count}' to count '{name}'")));
                }
                counts.push(count.to_string());
                Ok(())
            })?;
        }
        let count = (!counts.is_empty()).then(|| {
            quote! {
                fields.last_mut().expect("a field was pushed").count =
                    ::std::vec![#(::std::string::String::from(#counts)),*];
            }
        });
        pushes.push(quote! {
            <#field_ty as ::caravan_schemas::describe::FieldKind>::push(
                stringify!(#name),
                ::core::mem::offset_of!(#ty, #name),
                &mut fields,
            );
            #count
        });
    }
    let field_types = fields.iter().map(|f| &f.ty);
    Ok(quote! {
        impl ::caravan_schemas::describe::ElementKind for #ty {
            const ELEMENT: ::caravan_schemas::describe::Element =
                ::caravan_schemas::describe::Element::Struct(stringify!(#ty));

            fn dependencies(out: &mut ::std::vec::Vec<::caravan_schemas::describe::TypeLayout>) {
                let me = ::caravan_schemas::type_name_of::<#ty>();
                if out.iter().any(|l| l.type_name == me) {
                    return;
                }
                <#ty as ::caravan_schemas::describe::Describe>::dependencies(out);
                out.push(<#ty as ::caravan_schemas::describe::Describe>::layout());
            }
        }

        impl ::caravan_schemas::describe::Describe for #ty {
            fn layout() -> ::caravan_schemas::describe::TypeLayout {
                let mut fields = ::std::vec::Vec::new();
                #(#pushes)*
                ::caravan_schemas::describe::TypeLayout {
                    name: stringify!(#ty),
                    type_name: ::caravan_schemas::type_name_of::<#ty>(),
                    size: ::core::mem::size_of::<#ty>(),
                    align: ::core::mem::align_of::<#ty>(),
                    fields,
                }
            }

            fn dependencies(out: &mut ::std::vec::Vec<::caravan_schemas::describe::TypeLayout>) {
                #(<#field_types as ::caravan_schemas::describe::FieldKind>::dependencies(out);)*
            }
        }
    })
}
